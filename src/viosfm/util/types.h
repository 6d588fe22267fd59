// Typed ids (as COLMAP's, so that COLMAP files round-trip) and their invalid values.
#pragma once

#include <cstdint>
#include <limits>

namespace viosfm {

using camera_t = uint32_t;      // unique id of a camera (intrinsics)
using image_t = uint32_t;       // unique id of an image
using point2D_t = uint32_t;     // index of a keypoint within an image
using point3D_t = uint64_t;     // unique id of a 3D point
using image_pair_t = uint64_t;  // id of an unordered image pair (COLMAP's formula)

inline constexpr camera_t kInvalidCameraId = std::numeric_limits<camera_t>::max();
inline constexpr image_t kInvalidImageId = std::numeric_limits<image_t>::max();
inline constexpr point2D_t kInvalidPoint2DIdx = std::numeric_limits<point2D_t>::max();
inline constexpr point3D_t kInvalidPoint3DId = std::numeric_limits<point3D_t>::max();

}  // namespace viosfm

// Local features and matches: keypoints in raw (distorted) pixel coordinates
// in viosfm's convention (the centre of the top-left pixel is (0, 0), as in
// OpenCV and Kalibr; io/colmap_convention.h converts to COLMAP's (0.5, 0.5)
// for COLMAP's files), 128-byte SIFT-like descriptors, and matches as pairs
// of keypoint indices.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "viosfm/util/types.h"

namespace viosfm {

struct FeatureKeypoint {
  float x = 0.0f;  // pixels
  float y = 0.0f;  // pixels
  // Affine shape [a11 a12; a21 a22] = scale * [cos -sin; sin cos] for SIFT.
  float a11 = 1.0f;
  float a12 = 0.0f;
  float a21 = 0.0f;
  float a22 = 1.0f;

  static FeatureKeypoint FromScaleOrientation(float x, float y, float scale, float orientation_rad);
  float Scale() const;
  float Orientation() const;  // rad
};

using FeatureKeypoints = std::vector<FeatureKeypoint>;
// One descriptor a row.
using FeatureDescriptors = Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct FeatureMatch {
  point2D_t point2D_idx1 = kInvalidPoint2DIdx;
  point2D_t point2D_idx2 = kInvalidPoint2DIdx;
};
using FeatureMatches = std::vector<FeatureMatch>;

// The (verified) matches of one image pair: match.point2D_idx1 indexes
// image_id1's keypoints, point2D_idx2 image_id2's. Either order of the ids.
struct ImagePairMatches {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  FeatureMatches matches;
  // Accepted by RANSAC alone across a gap in the VIO's poses whose relative
  // pose step 1 rejected (PairDecision::vio_contradicted).
  bool vio_contradicted = false;
};

// COLMAP's pair id: ordered so that image_id1 < image_id2,
// pair_id = kMaxNumImages * image_id1 + image_id2 with kMaxNumImages = 2^31 - 1.
inline constexpr uint64_t kMaxNumImages = 2147483647;
image_pair_t ImagePairToPairId(image_t image_id1, image_t image_id2);
std::pair<image_t, image_t> PairIdToImagePair(image_pair_t pair_id);
// Whether (image_id1, image_id2) must be swapped to be in pair-id order.
inline bool SwapImagePair(image_t image_id1, image_t image_id2) {
  return image_id1 > image_id2;
}

}  // namespace viosfm

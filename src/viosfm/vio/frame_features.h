// What the VIO front end (feature_tracker.h) hands to the back end for each
// image: the tracked corners, each with an id that persists while the corner
// is tracked, in raw pixels and in undistorted normalised camera coordinates.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "viosfm/util/timestamp.h"

namespace viosfm {

// Pixel thresholds of the VIO that stand for angles (parallax, epipolar
// distances, the KLT window's reach) are stated for a camera of this focal
// length (VINS-Mono's virtual camera, about EuRoC's 458 px) and scaled by
// the camera's focal length over it, so that a 1280x720 camera at 906 px
// behaves as a 752x480 one at 458 px. Measurement noise (pixel sigmas,
// reprojection thresholds, the forward-backward check) stays in pixels.
constexpr double kReferenceFocalLengthPx = 460.0;

struct FeatureObservation {
  // Unique over the whole sequence; the same id in two frames is the same
  // scene point (as far as the tracker knows).
  uint64_t track_id = 0;
  // Raw (distorted) pixel position, viosfm's convention (pixel centres at
  // integer coordinates).
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  // Undistorted normalised camera coordinates (x/z, y/z).
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();
  // Frames this track has been seen in, this one included (>= 1).
  int track_length = 1;
};

struct FrameFeatures {
  timestamp_ns_t timestamp_ns = 0;
  std::vector<FeatureObservation> observations;
  // The front end's keyframe decision: enough parallax to the last keyframe,
  // or too few tracks left from it.
  bool is_keyframe = false;
  // Mean parallax (pixels, rotation not compensated) of the tracks shared
  // with the last keyframe, and how many there are.
  double parallax_px = 0.0;
  int num_tracked_from_keyframe = 0;
};

}  // namespace viosfm

// How well a reconstruction's images fix each camera's position: the
// covariance of the camera centre in the world, for the pose priors that
// `viosfm export` gives COLMAP (io/colmap_pose_priors.h).
//
// Two parts, each a lower bound of the true uncertainty's own part:
//
//  * Local: the camera's pose from its 2D-3D observations with the points
//    held, by Gauss-Newton: J^T J / sigma^2 over its observations, for the
//    six parameters (camera centre in the world, rotation), inverted; the
//    centre's 3x3 block. sigma is the keypoints' standard deviation per
//    coordinate, by default the model's own (the root mean square of its
//    reprojection errors per coordinate). It ignores the points' own
//    uncertainty and the drift that accumulates along a walk.
//  * Scale: a metric scale known to a relative standard deviation s (the
//    IMU scale's, summary.json) moves a camera along its offset d from the
//    first registered image (the mapper's gauge) by s |d|: s^2 d d^T.
//
// A camera with fewer than three observations, or whose observations leave
// a direction of its pose free, gets no entry (the caller's fallback).
#pragma once

#include <Eigen/Core>
#include <map>

#include "viosfm/scene/reconstruction.h"

namespace viosfm {

struct CameraPositionCovarianceOptions {
  // Standard deviation of a keypoint's position per coordinate (px); <= 0:
  // the model's (root mean square of the reprojection errors' coordinates).
  double keypoint_sigma_px = 0.0;
  // Relative standard deviation of the model's metric scale (0: exact).
  double scale_sigma = 0.0;
};

struct CameraPositionCovariances {
  double keypoint_sigma_px = 0.0;  // the sigma used
  // Covariance of the camera centre in the world (m^2), by registered image.
  std::map<image_t, Eigen::Matrix3d> by_image;
};

CameraPositionCovariances ComputeCameraPositionCovariances(
    const Reconstruction& reconstruction, const CameraPositionCovarianceOptions& options);

}  // namespace viosfm

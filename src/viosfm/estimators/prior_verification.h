// VIO-aided geometric verification (the paper's section "VIO-Aided Geometric
// Verification", eq. 1): the relative pose of an image pair predicted by VIO
// gives a fundamental matrix F = K2^-T [t]x R K1^-1; each tentative match is
// scored by the pixel distance EE of its point in image 2 from the epipolar
// line F x1, is an outlier if EE > T_EE, and the pair is rejected when the
// ratio of outliers exceeds a bound. It rejects pairs whose matches agree
// with *some* epipolar geometry (so RANSAC accepts them) but not with where
// the cameras actually were: visually identical places that are physically
// apart.
//
// Pixels: points are given as undistorted normalised coordinates and mapped
// to pixels of an ideal pinhole camera with each camera's focal lengths and
// principal point (K = CalibrationMatrix(camera)); EE is in those pixels.
//
// Near-zero baseline (static camera or pure rotation): F = K2^-T [t]x R K1^-1
// vanishes as t -> 0 and the epipolar lines are undefined. When the VIO
// baseline |t| is below min_baseline_m, each match is scored instead by the
// infinite-homography transfer error |x2 - H x1|, H = K2 R K1^-1 (exact for
// points at infinity; a point at depth d adds at most f |t| / d pixels of
// parallax). The same substitution is used for a single match whose epipolar
// line is undefined (x1 at the epipole).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

struct PriorVerificationOptions {
  // T_EE: a match whose epipolar error exceeds it is an outlier, pixels.
  // Default 20 (the paper's).
  double max_epipolar_error_px = 20.0;
  // The pair is rejected when outliers / matches exceeds it, in [0, 1].
  // Default 0.5 (the paper's).
  double max_outlier_ratio = 0.5;
  // Below this VIO baseline the rotation-only transfer error replaces EE,
  // metres. Default 0.01 (a point 0.25 m away then moves at most 0.04 f
  // pixels, 18 px at f = 460, below T_EE).
  double min_baseline_m = 0.01;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct PriorVerificationResult {
  bool accepted = false;
  // The baseline was below min_baseline_m: errors are transfer errors.
  bool rotation_only = false;
  int num_matches = 0;
  int num_outliers = 0;
  // num_outliers / num_matches; 1 when there are no matches (nothing
  // supports the pair, which is then rejected).
  double outlier_ratio = 1.0;
  // Per match, in the input order: EE (or the transfer error), pixels;
  // infinity when undefined (a point that rotates behind camera 2).
  std::vector<double> errors_px;
};

// cam2_from_cam1 from the VIO body poses and the camera extrinsics:
// (world_from_body2 * body_from_cam2)^-1 * world_from_body1 * body_from_cam1.
Rigid3d RelativePoseFromVio(const Rigid3d& world_from_body1, const Rigid3d& world_from_body2,
                            const Rigid3d& body_from_cam1, const Rigid3d& body_from_cam2);

// Scores the matches of a pair under the predicted relative pose
// cam2_from_cam1 (metric translation). points*_normalized hold the
// undistorted normalised coordinates of all keypoints of each image
// (indexed by point2D_idx); matches index into them.
PriorVerificationResult VerifyPairWithPrior(const Camera& camera1, const Camera& camera2,
                                            const Rigid3d& cam2_from_cam1,
                                            const std::vector<Eigen::Vector2d>& points1_normalized,
                                            const std::vector<Eigen::Vector2d>& points2_normalized,
                                            const FeatureMatches& matches,
                                            const PriorVerificationOptions& options);

// The same from the VIO poses of the two frames and one camera rig
// (body_from_cam shared by both images).
PriorVerificationResult VerifyPairWithVioPoses(
    const Camera& camera1, const Camera& camera2, const Rigid3d& world_from_body1,
    const Rigid3d& world_from_body2, const Rigid3d& body_from_cam,
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    const PriorVerificationOptions& options);

}  // namespace viosfm

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
//
// Depth consistency (not in the paper; on by default, check_depth = false
// gives the paper's test alone). The EE test only asks a match to lie on its
// epipolar line, and the point where the line passes through the match's
// infinite-depth position H x1 (H = K2 R K1^-1) always does. Two identical
// views stacked one above the other (identical floors) have matches with no
// image motion at all; the VIO baseline is large and vertical, so every
// epipolar line passes through its keypoint, EE ~ 0 and the pair passes.
// The VIO baseline is metric, though: a point at depth d moves along its
// epipolar line from H x1 towards the epipole by a parallax that grows as
// 1/d. For each match that passed EE, let p_D be the parallax, in pixels,
// that a point at max_scene_depth_m on the match's ray in image 1 would show
// in image 2; every point nearer than that shows at least p_D (the
// projection moves monotonically along the line as the inverse depth
// grows). The match is scored when p_D >= min_depth_parallax_px (far from
// the epipole and a large enough baseline: the bound is then clearly above
// the noise), and it is depth-inconsistent when its own parallax, measured
// along the line from H x1, is below p_D - depth_tolerance_px: its point
// would have to be farther than max_scene_depth_m, at infinity, or behind
// camera 1. Such a match is impossible under the VIO pose and counts as an
// outlier of the paper's ratio: the pair is rejected (reason "vio_depth")
// when (EE outliers + depth-inconsistent) / matches exceeds
// max_outlier_ratio while EE alone would accept it. Small baselines, pure
// rotation (rotation_only) and matches near the epipole are never scored, so
// the check leaves them to the EE test.
//
// Which matches it judges matters: tentative matches of a correct pair can
// include wrong ones that pass EE (on repeated structure seen along the
// baseline, e.g. identical doors along a corridor walked forwards, a door
// matched to the next one shows almost no motion, which lies on its radial
// epipolar line, and also on that of the true geometry, so RANSAC keeps it),
// and in a narrow corridor the correct far matches lie near the epipole and
// are not scored: the inconsistent ratio of such a correct pair is near 1.
// That is why the inconsistent matches count against all matches (most of
// them must be impossible to reject the pair) and not against the scored
// ones; the verification driver also removes them before RANSAC
// (matching/verification_driver.h).
#pragma once

#include <Eigen/Core>
#include <limits>
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

  // Depth consistency with the metric VIO baseline (see the top of the
  // file; not in the paper). Default true; false: the paper's EE test only.
  bool check_depth = true;
  // Farthest scene point expected, metres. Default 20 (rooms, halls,
  // corridors and a drone in an indoor hall such as EuRoC's machine hall:
  // farther structure is rare and mostly near the epipole of a
  // forward-moving camera, where matches are not scored).
  double max_scene_depth_m = 20.0;
  // Parallax tolerance for the VIO relative pose error and keypoint noise,
  // pixels. Default 20 (T_EE: the same allowance as the EE test).
  double depth_tolerance_px = 20.0;
  // A match is scored only if a point at max_scene_depth_m would show at
  // least this parallax, pixels. Default 40 (twice depth_tolerance_px, so a
  // zero-parallax match is at least one tolerance below the bound: at f =
  // 460 px a baseline of at least 1.7 m across the ray at 20 m).
  double min_depth_parallax_px = 40.0;

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
  // The paper's verdict (EE test alone); accepted additionally requires the
  // depth check not to reject.
  bool accepted_epipolar = false;
  // The depth check scored at least one match.
  bool depth_applied = false;
  // EE accepted the pair, and EE outliers + depth-inconsistent matches
  // exceed max_outlier_ratio of the matches.
  bool depth_rejected = false;
  int num_depth_scored = 0;        // matches passing EE whose parallax bound is informative
  int num_depth_inconsistent = 0;  // of those, the depth-inconsistent ones
  // num_depth_inconsistent / num_depth_scored; NaN when not applied.
  double depth_inconsistent_ratio = std::numeric_limits<double>::quiet_NaN();
  // Per match, in the input order: depth-inconsistent (empty without the
  // check).
  std::vector<bool> depth_inconsistent;
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

// The depth-consistency check alone (see the top of the file) on `matches`:
// those within T_EE of their epipolar lines are scored. Nothing is scored
// below min_baseline_m.
struct DepthConsistencyResult {
  int num_scored = 0;
  int num_inconsistent = 0;
  // num_inconsistent / num_scored; NaN when none is scored.
  double inconsistent_ratio = std::numeric_limits<double>::quiet_NaN();
  // Per input match: scored and depth-inconsistent.
  std::vector<bool> inconsistent;
};
DepthConsistencyResult CheckDepthConsistency(const Camera& camera1, const Camera& camera2,
                                             const Rigid3d& cam2_from_cam1,
                                             const std::vector<Eigen::Vector2d>& points1_normalized,
                                             const std::vector<Eigen::Vector2d>& points2_normalized,
                                             const FeatureMatches& matches,
                                             const PriorVerificationOptions& options);

// How far a relative pose (its rotation and its translation's direction,
// the 5 degrees of freedom of an essential matrix) is from the VIO's, under
// the VIO model's covariance of the relative pose (the 6x6 covariance of
// its residual [Log(R_E); t_E], scene/vio_uncertainty.h) taken to those 5:
// the rotation, and the translation's error across the VIO's direction over
// the VIO's baseline. The VIO's pose needs a baseline (checked).
class RelativePoseDrift {
 public:
  RelativePoseDrift(const Rigid3d& vio_cam2_from_cam1,
                    const Eigen::Matrix<double, 6, 6>& covariance);
  // The deviation of `pose` (any translation length but 0) from the VIO's:
  // [Log(R R_vio^T); the direction's angle from the VIO's along its great
  // circle, in the VIO direction's tangent plane], and its derivative with
  // respect to RelativePosePlus's step at `pose` (when `jacobian` is given).
  Eigen::Matrix<double, 5, 1> Deviation(const Rigid3d& pose,
                                        Eigen::Matrix<double, 5, 5>* jacobian) const;
  // The deviation's Mahalanobis distance.
  double Mahalanobis(const Rigid3d& pose) const;
  const Eigen::Matrix<double, 5, 5>& information() const { return information_; }

 private:
  double baseline_m_;
  Eigen::Vector3d direction_;
  Eigen::Quaterniond rotation_;
  Eigen::Matrix<double, 3, 2> plane_;
  Eigen::Matrix<double, 5, 5> information_;
};

// The VIO's relative pose corrected by the matches, within the VIO's
// expected drift between the two frames. A band wide enough for the drift
// of far-apart frames (a loop's two visits) judges each match on its own,
// so the drift's slack lets in matches no single pose explains (on a
// corridor of identical doors, far-apart views facing opposite ways whose
// matches lie on the radial epipolar lines of the walking direction; see
// docs/benchmarks.md, section "VIO-aided verification against ground truth").
// The drift is one rigid error
// of the whole relative pose, though: this finds that one error, and the
// pair is then judged with the fixed T_EE under the corrected pose.
//
// Starting from cam2_from_cam1 (the VIO's, metric), the rotation and the
// translation's direction (the 5 degrees of freedom of the essential
// matrix; the VIO's baseline length is kept) are refined by Gauss-Newton on
// the Sampson errors of the matches (at most 256, evenly spread over
// `matches`) under a Cauchy loss whose scale shrinks
// from search_band_px (the band the drift allows) to kFinalScalePx, each
// match weighed as 1 px keypoint noise, plus the correction's Mahalanobis
// distance under `covariance` (RelativePoseDrift). A correction
// farther than max_mahalanobis from the VIO's pose is not the VIO's drift:
// the VIO's pose is returned unchanged. Below options.min_baseline_m (no
// direction to correct) and with fewer than five matches nothing is done.
struct DriftCorrection {
  Rigid3d cam2_from_cam1;  // the corrected pose (or the input), metric
  bool corrected = false;  // a correction within max_mahalanobis was found
  // Of the correction found (also when rejected); NaN when nothing was done.
  double mahalanobis = std::numeric_limits<double>::quiet_NaN();
};
DriftCorrection CorrectRelativePoseWithinDrift(
    const Camera& camera1, const Camera& camera2, const Rigid3d& cam2_from_cam1,
    const Eigen::Matrix<double, 6, 6>& covariance,
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    double search_band_px, double max_mahalanobis, const PriorVerificationOptions& options);

// The same from the VIO poses of the two frames and one camera rig
// (body_from_cam shared by both images).
PriorVerificationResult VerifyPairWithVioPoses(
    const Camera& camera1, const Camera& camera2, const Rigid3d& world_from_body1,
    const Rigid3d& world_from_body2, const Rigid3d& body_from_cam,
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    const PriorVerificationOptions& options);

}  // namespace viosfm

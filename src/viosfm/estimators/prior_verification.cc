#include "viosfm/estimators/prior_verification.h"

#include <cmath>
#include <limits>
#include <optional>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// |x2 - H x1| with H = K2 R K1^-1 in pixels, from normalised coordinates;
// infinity if the rotated ray points behind camera 2.
double RotationTransferError(const Eigen::Matrix3d& calibration2, const Eigen::Matrix3d& rotation,
                             const Eigen::Vector2d& point1, const Eigen::Vector2d& pixel2) {
  const Eigen::Vector3d ray = rotation * point1.homogeneous();
  if (!(ray.z() > 0.0)) return std::numeric_limits<double>::infinity();
  return ((calibration2 * ray).hnormalized() - pixel2).norm();
}

// Depth consistency of one match (see the header): nullopt when not scored,
// else whether the match is depth-inconsistent.
std::optional<bool> DepthInconsistent(const Eigen::Matrix3d& calibration2,
                                      const Eigen::Vector3d& rotated_ray,
                                      const Eigen::Vector3d& translation,
                                      const Eigen::Vector2d& pixel2,
                                      const PriorVerificationOptions& options) {
  constexpr double kMinDepth = 1e-6;  // z of a ray that still projects
  const Eigen::Vector3d at_infinity = rotated_ray;
  const Eigen::Vector3d at_max_depth = rotated_ray + translation / options.max_scene_depth_m;
  if (!(at_infinity.z() > kMinDepth) || !(at_max_depth.z() > kMinDepth)) return std::nullopt;
  const Eigen::Vector2d pixel_infinity = (calibration2 * at_infinity).hnormalized();
  const Eigen::Vector2d pixel_max_depth = (calibration2 * at_max_depth).hnormalized();
  const Eigen::Vector2d along = pixel_max_depth - pixel_infinity;
  const double bound = along.norm();
  if (!(bound >= options.min_depth_parallax_px)) return std::nullopt;
  const double parallax = (pixel2 - pixel_infinity).dot(along / bound);
  return parallax < bound - options.depth_tolerance_px;
}

}  // namespace

std::string PriorVerificationOptions::Validate() const {
  if (!(max_epipolar_error_px > 0.0)) return "max_epipolar_error_px must be > 0";
  if (!(max_outlier_ratio >= 0.0 && max_outlier_ratio <= 1.0)) {
    return "max_outlier_ratio must be in [0, 1]";
  }
  if (!(min_baseline_m >= 0.0) || !std::isfinite(min_baseline_m)) {
    return "min_baseline_m must be >= 0 and finite";
  }
  if (!(max_scene_depth_m > 0.0) || !std::isfinite(max_scene_depth_m)) {
    return "max_scene_depth_m must be > 0 and finite";
  }
  if (!(depth_tolerance_px >= 0.0) || !std::isfinite(depth_tolerance_px)) {
    return "depth_tolerance_px must be >= 0 and finite";
  }
  if (!(min_depth_parallax_px > 0.0) || !std::isfinite(min_depth_parallax_px)) {
    return "min_depth_parallax_px must be > 0 and finite";
  }
  return "";
}

Rigid3d RelativePoseFromVio(const Rigid3d& world_from_body1, const Rigid3d& world_from_body2,
                            const Rigid3d& body_from_cam1, const Rigid3d& body_from_cam2) {
  return (world_from_body2 * body_from_cam2).Inverse() * (world_from_body1 * body_from_cam1);
}

PriorVerificationResult VerifyPairWithPrior(const Camera& camera1, const Camera& camera2,
                                            const Rigid3d& cam2_from_cam1,
                                            const std::vector<Eigen::Vector2d>& points1_normalized,
                                            const std::vector<Eigen::Vector2d>& points2_normalized,
                                            const FeatureMatches& matches,
                                            const PriorVerificationOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const Eigen::Matrix3d calibration1 = CalibrationMatrix(camera1);
  const Eigen::Matrix3d calibration2 = CalibrationMatrix(camera2);
  const Eigen::Matrix3d rotation = cam2_from_cam1.rotation.toRotationMatrix();
  const Eigen::Matrix3d fundamental =
      FundamentalFromRelativePose(cam2_from_cam1, calibration1, calibration2);

  PriorVerificationResult result;
  result.rotation_only = cam2_from_cam1.translation.norm() < options.min_baseline_m;
  result.num_matches = static_cast<int>(matches.size());
  result.errors_px.resize(matches.size());
  FeatureMatches epipolar_inliers;
  for (size_t i = 0; i < matches.size(); ++i) {
    VIOSFM_CHECK_LT(matches[i].point2D_idx1, points1_normalized.size());
    VIOSFM_CHECK_LT(matches[i].point2D_idx2, points2_normalized.size());
    const Eigen::Vector2d& point1 = points1_normalized[matches[i].point2D_idx1];
    const Eigen::Vector2d pixel1 = (calibration1 * point1.homogeneous()).hnormalized();
    const Eigen::Vector2d pixel2 =
        (calibration2 * points2_normalized[matches[i].point2D_idx2].homogeneous()).hnormalized();
    double error = std::numeric_limits<double>::infinity();
    if (!result.rotation_only) error = EpipolarLineDistance(fundamental, pixel1, pixel2);
    if (!std::isfinite(error))
      error = RotationTransferError(calibration2, rotation, point1, pixel2);
    result.errors_px[i] = error;
    if (!(error <= options.max_epipolar_error_px)) {
      ++result.num_outliers;
    } else {
      epipolar_inliers.push_back(matches[i]);
    }
  }
  if (result.num_matches > 0) {
    result.outlier_ratio =
        static_cast<double>(result.num_outliers) / static_cast<double>(result.num_matches);
    result.accepted_epipolar = result.outlier_ratio <= options.max_outlier_ratio;
  }
  if (options.check_depth) {
    const DepthConsistencyResult depth =
        CheckDepthConsistency(camera1, camera2, cam2_from_cam1, points1_normalized,
                              points2_normalized, epipolar_inliers, options);
    result.depth_applied = depth.num_scored > 0;
    result.num_depth_scored = depth.num_scored;
    result.num_depth_inconsistent = depth.num_inconsistent;
    result.depth_inconsistent_ratio = depth.inconsistent_ratio;
    // epipolar_inliers are in input order: map the flags back.
    result.depth_inconsistent.assign(matches.size(), false);
    for (size_t i = 0, k = 0; i < matches.size(); ++i) {
      if (result.errors_px[i] <= options.max_epipolar_error_px) {
        result.depth_inconsistent[i] = depth.inconsistent[k++];
      }
    }
    result.depth_rejected =
        result.accepted_epipolar &&
        static_cast<double>(result.num_outliers + result.num_depth_inconsistent) >
            options.max_outlier_ratio * static_cast<double>(result.num_matches);
  }
  result.accepted = result.accepted_epipolar && !result.depth_rejected;
  return result;
}

DepthConsistencyResult CheckDepthConsistency(const Camera& camera1, const Camera& camera2,
                                             const Rigid3d& cam2_from_cam1,
                                             const std::vector<Eigen::Vector2d>& points1_normalized,
                                             const std::vector<Eigen::Vector2d>& points2_normalized,
                                             const FeatureMatches& matches,
                                             const PriorVerificationOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  DepthConsistencyResult result;
  result.inconsistent.assign(matches.size(), false);
  if (cam2_from_cam1.translation.norm() < options.min_baseline_m) return result;
  const Eigen::Matrix3d calibration1 = CalibrationMatrix(camera1);
  const Eigen::Matrix3d calibration2 = CalibrationMatrix(camera2);
  const Eigen::Matrix3d rotation = cam2_from_cam1.rotation.toRotationMatrix();
  const Eigen::Matrix3d fundamental =
      FundamentalFromRelativePose(cam2_from_cam1, calibration1, calibration2);
  result.inconsistent.assign(matches.size(), false);
  for (size_t i = 0; i < matches.size(); ++i) {
    const FeatureMatch& match = matches[i];
    VIOSFM_CHECK_LT(match.point2D_idx1, points1_normalized.size());
    VIOSFM_CHECK_LT(match.point2D_idx2, points2_normalized.size());
    const Eigen::Vector2d& point1 = points1_normalized[match.point2D_idx1];
    const Eigen::Vector2d pixel1 = (calibration1 * point1.homogeneous()).hnormalized();
    const Eigen::Vector2d pixel2 =
        (calibration2 * points2_normalized[match.point2D_idx2].homogeneous()).hnormalized();
    if (!(EpipolarLineDistance(fundamental, pixel1, pixel2) <= options.max_epipolar_error_px)) {
      continue;
    }
    const std::optional<bool> inconsistent = DepthInconsistent(
        calibration2, rotation * point1.homogeneous(), cam2_from_cam1.translation, pixel2, options);
    if (!inconsistent) continue;
    ++result.num_scored;
    if (*inconsistent) {
      ++result.num_inconsistent;
      result.inconsistent[i] = true;
    }
  }
  if (result.num_scored > 0) {
    result.inconsistent_ratio =
        static_cast<double>(result.num_inconsistent) / static_cast<double>(result.num_scored);
  }
  return result;
}

PriorVerificationResult VerifyPairWithVioPoses(
    const Camera& camera1, const Camera& camera2, const Rigid3d& world_from_body1,
    const Rigid3d& world_from_body2, const Rigid3d& body_from_cam,
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    const PriorVerificationOptions& options) {
  return VerifyPairWithPrior(
      camera1, camera2,
      RelativePoseFromVio(world_from_body1, world_from_body2, body_from_cam, body_from_cam),
      points1_normalized, points2_normalized, matches, options);
}

}  // namespace viosfm

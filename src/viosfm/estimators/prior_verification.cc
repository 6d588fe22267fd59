#include "viosfm/estimators/prior_verification.h"

#include <cmath>
#include <limits>

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

}  // namespace

std::string PriorVerificationOptions::Validate() const {
  if (!(max_epipolar_error_px > 0.0)) return "max_epipolar_error_px must be > 0";
  if (!(max_outlier_ratio >= 0.0 && max_outlier_ratio <= 1.0)) {
    return "max_outlier_ratio must be in [0, 1]";
  }
  if (!(min_baseline_m >= 0.0) || !std::isfinite(min_baseline_m)) {
    return "min_baseline_m must be >= 0 and finite";
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
    if (!(error <= options.max_epipolar_error_px)) ++result.num_outliers;
  }
  if (result.num_matches > 0) {
    result.outlier_ratio =
        static_cast<double>(result.num_outliers) / static_cast<double>(result.num_matches);
    result.accepted = result.outlier_ratio <= options.max_outlier_ratio;
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

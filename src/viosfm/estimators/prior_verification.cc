#include "viosfm/estimators/prior_verification.h"

#include <cmath>
#include <limits>
#include <optional>

#include "viosfm/estimators/essential_matrix.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/lie.h"
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

RelativePoseDrift::RelativePoseDrift(const Rigid3d& vio_cam2_from_cam1,
                                     const Eigen::Matrix<double, 6, 6>& covariance)
    : baseline_m_(vio_cam2_from_cam1.translation.norm()) {
  VIOSFM_CHECK_GT(baseline_m_, 0.0) << "a relative pose without a baseline has no direction";
  direction_ = vio_cam2_from_cam1.translation / baseline_m_;
  rotation_ = vio_cam2_from_cam1.rotation.normalized();
  plane_ = DirectionTangentBasis(direction_);
  // The rotation as it is, the direction's step in the plane orthogonal to
  // the VIO's direction (the translation's error across it, over the
  // baseline).
  Eigen::Matrix<double, 5, 6> to_local = Eigen::Matrix<double, 5, 6>::Zero();
  to_local.topLeftCorner<3, 3>().setIdentity();
  to_local.bottomRightCorner<2, 3>() = plane_.transpose() / baseline_m_;
  Eigen::Matrix<double, 5, 5> local_covariance = to_local * covariance * to_local.transpose();
  local_covariance.diagonal().array() += 1e-12;  // a floor: never singular
  information_ = local_covariance.inverse();
}

Eigen::Matrix<double, 5, 1> RelativePoseDrift::Deviation(
    const Rigid3d& pose, Eigen::Matrix<double, 5, 5>* jacobian) const {
  Eigen::Matrix<double, 5, 1> d;
  d.head<3>() = So3Log(pose.rotation * rotation_.conjugate());
  // The direction's angle from the VIO's, along its great circle (a
  // reversed direction is half a turn away, not zero).
  const Eigen::Vector3d translation = pose.translation.normalized();
  const Eigen::Vector2d across = plane_.transpose() * translation;
  const double angle = std::atan2(across.norm(), translation.dot(direction_));
  d.tail<2>() = across.norm() > 1e-15 ? Eigen::Vector2d(angle * across.normalized())
                                      : Eigen::Vector2d(angle, 0.0);
  if (jacobian != nullptr) {
    jacobian->setZero();
    jacobian->topLeftCorner<3, 3>().setIdentity();
    jacobian->bottomRightCorner<2, 2>() = plane_.transpose() * DirectionTangentBasis(translation);
  }
  return d;
}

double RelativePoseDrift::Mahalanobis(const Rigid3d& pose) const {
  const Eigen::Matrix<double, 5, 1> d = Deviation(pose, nullptr);
  return std::sqrt(std::max(0.0, d.dot(information_ * d)));
}

DriftCorrection CorrectRelativePoseWithinDrift(
    const Camera& camera1, const Camera& camera2, const Rigid3d& cam2_from_cam1,
    const Eigen::Matrix<double, 6, 6>& covariance,
    const std::vector<Eigen::Vector2d>& points1_normalized,
    const std::vector<Eigen::Vector2d>& points2_normalized, const FeatureMatches& matches,
    double search_band_px, double max_mahalanobis, const PriorVerificationOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  constexpr double kFinalScalePx = 2.0;  // the Cauchy scale at the end
  constexpr double kKeypointSigmaPx = 1.0;
  constexpr int kIterationsPerScale = 4;
  constexpr size_t kMaxMatches = 256;  // evenly spread over the pair's matches
  DriftCorrection result;
  result.cam2_from_cam1 = cam2_from_cam1;
  const double baseline = cam2_from_cam1.translation.norm();
  if (baseline < options.min_baseline_m || matches.size() < 5) return result;
  const RelativePoseDrift drift(cam2_from_cam1, covariance);

  std::vector<Eigen::Vector2d> points1, points2;
  const size_t num_used = std::min(matches.size(), kMaxMatches);
  points1.reserve(num_used);
  points2.reserve(num_used);
  for (size_t k = 0; k < num_used; ++k) {
    const FeatureMatch& match = matches[k * matches.size() / num_used];
    VIOSFM_CHECK_LT(match.point2D_idx1, points1_normalized.size());
    VIOSFM_CHECK_LT(match.point2D_idx2, points2_normalized.size());
    points1.push_back(points1_normalized[match.point2D_idx1]);
    points2.push_back(points2_normalized[match.point2D_idx2]);
  }
  const double focal = 0.5 * (MeanFocalLength(camera1) + MeanFocalLength(camera2));
  const double sigma = kKeypointSigmaPx / focal;

  Rigid3d pose(cam2_from_cam1.rotation.normalized(), cam2_from_cam1.translation / baseline);
  Eigen::VectorXd residuals;
  Eigen::Matrix<double, Eigen::Dynamic, 5> jacobian;
  for (double scale_px = std::max(search_band_px, kFinalScalePx);;
       scale_px = std::max(0.5 * scale_px, kFinalScalePx)) {
    const double scale = scale_px / focal;
    for (int iteration = 0; iteration < kIterationsPerScale; ++iteration) {
      RelativePoseSampsonResiduals(pose, points1, points2, &residuals, &jacobian);
      Eigen::Matrix<double, 5, 5> normal = Eigen::Matrix<double, 5, 5>::Zero();
      Eigen::Matrix<double, 5, 1> gradient = Eigen::Matrix<double, 5, 1>::Zero();
      for (Eigen::Index i = 0; i < residuals.size(); ++i) {
        const double u = residuals[i] / scale;
        const double weight = 1.0 / (1.0 + u * u) / (sigma * sigma);
        normal += weight * jacobian.row(i).transpose() * jacobian.row(i);
        gradient += weight * residuals[i] * jacobian.row(i).transpose();
      }
      Eigen::Matrix<double, 5, 5> d_jacobian;
      const Eigen::Matrix<double, 5, 1> d = drift.Deviation(pose, &d_jacobian);
      normal += d_jacobian.transpose() * drift.information() * d_jacobian;
      gradient += d_jacobian.transpose() * drift.information() * d;
      const Eigen::Matrix<double, 5, 1> step = normal.ldlt().solve(-gradient);
      if (!step.allFinite()) break;
      pose = RelativePosePlus(pose, step);
      if (step.norm() < 1e-7) break;  // rad, and rad of the direction
    }
    if (scale_px <= kFinalScalePx) break;
  }
  result.mahalanobis = drift.Mahalanobis(pose);
  if (!(result.mahalanobis <= max_mahalanobis)) return result;
  result.corrected = true;
  result.cam2_from_cam1 = Rigid3d(pose.rotation, baseline * pose.translation);
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

#include "viosfm/scene/vio_uncertainty.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

bool NonNegative(double value) {
  return value >= 0.0 && std::isfinite(value);
}

}  // namespace

VioUncertaintyModel VioUncertaintyModel::Scaled(double factor) const {
  VIOSFM_CHECK(factor > 0.0 && std::isfinite(factor)) << "factor " << factor;
  VioUncertaintyModel scaled = *this;
  for (double* rate :
       {&scaled.position_per_sqrt_m, &scaled.position_per_sqrt_s, &scaled.yaw_per_sqrt_m,
        &scaled.yaw_per_sqrt_s, &scaled.yaw_per_sqrt_rad, &scaled.tilt_per_sqrt_s,
        &scaled.scale_sigma, &scaled.relative_scale_sigma, &scaled.position_noise_m,
        &scaled.rotation_noise_rad, &scaled.correlated_position_noise_m,
        &scaled.correlated_rotation_noise_rad}) {
    *rate *= factor;
  }
  return scaled;
}

VioUncertaintyModel VioUncertaintyModel::Exact() {
  VioUncertaintyModel model;
  model.position_per_sqrt_m = 0.0;
  model.position_per_sqrt_s = 0.0;
  model.yaw_per_sqrt_m = 0.0;
  model.yaw_per_sqrt_s = 0.0;
  model.yaw_per_sqrt_rad = 0.0;
  model.tilt_per_sqrt_s = 0.0;
  model.scale_sigma = 0.0;
  model.relative_scale_sigma = 0.0;
  model.position_noise_m = 1e-4;
  model.rotation_noise_rad = 1e-4;
  model.correlated_position_noise_m = 0.0;
  model.correlated_rotation_noise_rad = 0.0;
  return model;
}

VioUncertaintyModel VioUncertaintyModel::WithinSegment() const {
  VioUncertaintyModel model = *this;
  model.scale_sigma = relative_scale_sigma;
  return model;
}

std::string VioUncertaintyModel::Validate() const {
  const std::pair<const char*, double> rates[] = {
      {"position_per_sqrt_m", position_per_sqrt_m},
      {"position_per_sqrt_s", position_per_sqrt_s},
      {"yaw_per_sqrt_m", yaw_per_sqrt_m},
      {"yaw_per_sqrt_s", yaw_per_sqrt_s},
      {"yaw_per_sqrt_rad", yaw_per_sqrt_rad},
      {"tilt_per_sqrt_s", tilt_per_sqrt_s},
      {"scale_sigma", scale_sigma},
      {"relative_scale_sigma", relative_scale_sigma},
      {"correlated_position_noise_m", correlated_position_noise_m},
      {"correlated_rotation_noise_rad", correlated_rotation_noise_rad},
  };
  for (const auto& [name, value] : rates) {
    if (!NonNegative(value)) return std::string(name) + " must be >= 0";
  }
  // The frame noise keeps every covariance positive definite.
  if (!(position_noise_m > 0.0) || !std::isfinite(position_noise_m)) {
    return "position_noise_m must be > 0";
  }
  if (!(rotation_noise_rad > 0.0) || !std::isfinite(rotation_noise_rad)) {
    return "rotation_noise_rad must be > 0";
  }
  if (!(noise_correlation_s > 0.0) || !std::isfinite(noise_correlation_s)) {
    return "noise_correlation_s must be > 0";
  }
  return "";
}

std::vector<std::pair<std::string, std::string>> VioUncertaintyModel::ToKeyValues() const {
  return OptionsToKeyValues(*this);
}

namespace {

// The covariance of RelativePoseCovariance, with or without the frames' own
// noise.
Eigen::Matrix<double, 6, 6> RelativePoseCovarianceOf(const VioUncertaintyModel& model,
                                                     const VioSample& frame1,
                                                     const VioSample& frame2,
                                                     bool with_frame_noise) {
  VIOSFM_CHECK(model.Check()) << model.Validate();
  VIOSFM_CHECK_EQ(frame1.odometer.segment, frame2.odometer.segment)
      << "a relative pose across VIO segments";
  const double dt = std::abs(static_cast<double>(frame2.timestamp_ns - frame1.timestamp_ns)) * 1e-9;
  const double distance = std::abs(frame2.odometer.distance_m - frame1.odometer.distance_m);
  const double turned = std::abs(frame2.odometer.rotation_rad - frame1.odometer.rotation_rad);
  const Eigen::Vector3d d = frame2.world_from_cam.translation - frame1.world_from_cam.translation;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();

  // World-frame covariance of [rotation error; translation error].
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  auto rot = cov.topLeftCorner<3, 3>();
  auto pos = cov.bottomRightCorner<3, 3>();
  auto pos_rot = cov.bottomLeftCorner<3, 3>();  // cov(translation, rotation)

  // Drift between the frames.
  const double tilt_var = model.tilt_per_sqrt_s * model.tilt_per_sqrt_s * dt;
  const double yaw_var = model.yaw_per_sqrt_s * model.yaw_per_sqrt_s * dt +
                         model.yaw_per_sqrt_m * model.yaw_per_sqrt_m * distance +
                         model.yaw_per_sqrt_rad * model.yaw_per_sqrt_rad * turned;
  rot(0, 0) += tilt_var;
  rot(1, 1) += tilt_var;
  rot(2, 2) += yaw_var;
  pos.diagonal().array() += model.position_per_sqrt_s * model.position_per_sqrt_s * dt +
                            model.position_per_sqrt_m * model.position_per_sqrt_m * distance;
  const Eigen::Vector3d lateral = up.cross(d);  // the direction a yaw error moves d
  pos += (yaw_var / 3.0) * lateral * lateral.transpose();
  pos_rot += (yaw_var / 2.0) * lateral * up.transpose();
  // Scale.
  pos += model.scale_sigma * model.scale_sigma * d * d.transpose();

  // Frame noise: n2 - n1 for both parts, and frame 1's rotation noise
  // through the lever arm d.
  const double rho = std::exp(-dt / model.noise_correlation_s);
  const auto add_frame_noise = [&](double white, double correlated, bool rotation) {
    const double var = white * white + correlated * correlated;  // per frame
    const double covar = correlated * correlated * rho;          // between the frames
    const double diff_var = 2.0 * (var - covar);
    if (rotation) {
      rot.diagonal().array() += diff_var;
      // t += [d]x n1: var [d]x var [d]x^T, cov(t, n2 - n1) = [d]x (covar - var).
      const Eigen::Matrix3d lever = Hat(d);
      pos += var * lever * lever.transpose();
      pos_rot += (covar - var) * lever;
    } else {
      pos.diagonal().array() += diff_var;
    }
  };
  if (with_frame_noise) {
    add_frame_noise(model.rotation_noise_rad, model.correlated_rotation_noise_rad, true);
    add_frame_noise(model.position_noise_m, model.correlated_position_noise_m, false);
  }
  cov.topRightCorner<3, 3>() = cov.bottomLeftCorner<3, 3>().transpose();

  // Into camera 2's frame.
  Eigen::Matrix<double, 6, 6> cam2_from_world = Eigen::Matrix<double, 6, 6>::Zero();
  const Eigen::Matrix3d r2t = frame2.world_from_cam.rotation.toRotationMatrix().transpose();
  cam2_from_world.topLeftCorner<3, 3>() = r2t;
  cam2_from_world.bottomRightCorner<3, 3>() = r2t;
  Eigen::Matrix<double, 6, 6> result = cam2_from_world * cov * cam2_from_world.transpose();
  return 0.5 * (result + result.transpose());
}

}  // namespace

Eigen::Matrix<double, 6, 6> RelativePoseCovariance(const VioUncertaintyModel& model,
                                                   const VioSample& frame1,
                                                   const VioSample& frame2) {
  return RelativePoseCovarianceOf(model, frame1, frame2, /*with_frame_noise=*/true);
}

Eigen::Matrix<double, 6, 6> RelativePoseDriftCovariance(const VioUncertaintyModel& model,
                                                        const VioSample& frame1,
                                                        const VioSample& frame2) {
  return RelativePoseCovarianceOf(model, frame1, frame2, /*with_frame_noise=*/false);
}

Eigen::Matrix<double, 6, 6> SqrtInformationFromCovariance(
    const Eigen::Matrix<double, 6, 6>& covariance) {
  // covariance = L L^T  =>  covariance^-1 = L^-T L^-1, S = L^-1 (lower
  // triangular; any S with S^T S = covariance^-1 weighs alike).
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(covariance);
  VIOSFM_CHECK(llt.info() == Eigen::Success) << "covariance not positive definite:\n" << covariance;
  const Eigen::Matrix<double, 6, 6> lower = llt.matrixL();
  return lower.triangularView<Eigen::Lower>().solve(Eigen::Matrix<double, 6, 6>::Identity());
}

RelativePoseSigmas LargestSigmas(const Eigen::Matrix<double, 6, 6>& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rotation(covariance.topLeftCorner<3, 3>(),
                                                                Eigen::EigenvaluesOnly);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> translation(
      covariance.bottomRightCorner<3, 3>(), Eigen::EigenvaluesOnly);
  RelativePoseSigmas sigmas;
  sigmas.rotation_rad = std::sqrt(std::max(0.0, rotation.eigenvalues().maxCoeff()));
  sigmas.translation_m = std::sqrt(std::max(0.0, translation.eigenvalues().maxCoeff()));
  return sigmas;
}

std::vector<int> SegmentsFromTimeGaps(const Trajectory& trajectory, timestamp_ns_t max_gap_ns) {
  std::vector<int> segments(trajectory.size(), 0);
  int segment = 0;
  for (size_t k = 1; k < trajectory.size(); ++k) {
    if (max_gap_ns > 0 &&
        trajectory.poses[k].timestamp_ns - trajectory.poses[k - 1].timestamp_ns > max_gap_ns) {
      ++segment;
    }
    segments[k] = segment;
  }
  return segments;
}

std::vector<VioOdometer> ComputeVioOdometers(const Trajectory& world_from_frame,
                                             const std::vector<int>& segments) {
  VIOSFM_CHECK(segments.empty() || segments.size() == world_from_frame.size())
      << segments.size() << " segment indices for " << world_from_frame.size() << " poses";
  std::vector<VioOdometer> odometers(world_from_frame.size());
  for (size_t k = 0; k < world_from_frame.size(); ++k) {
    VioOdometer& odometer = odometers[k];
    odometer.segment = segments.empty() ? 0 : segments[k];
    if (k > 0) {
      VIOSFM_CHECK_GE(odometer.segment, odometers[k - 1].segment) << "segments must not decrease";
    }
    if (k == 0 || odometer.segment != odometers[k - 1].segment) continue;
    const Rigid3d& before = world_from_frame.poses[k - 1].world_from_frame;
    const Rigid3d& after = world_from_frame.poses[k].world_from_frame;
    odometer.distance_m =
        odometers[k - 1].distance_m + (after.translation - before.translation).norm();
    odometer.rotation_rad =
        odometers[k - 1].rotation_rad + before.rotation.angularDistance(after.rotation);
  }
  return odometers;
}

}  // namespace viosfm

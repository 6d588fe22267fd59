#include "viosfm/sim/vio_emulator.h"

#include <cmath>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {

VioDriftOptions VioDriftOptions::Scaled(double factor) const {
  VioDriftOptions scaled = *this;
  scaled.position_walk_m_per_sqrt_m *= factor;
  scaled.yaw_walk_rad_per_sqrt_m *= factor;
  scaled.scale_error *= factor;
  scaled.position_jitter_m *= factor;
  scaled.rotation_jitter_rad *= factor;
  return scaled;
}

std::string VioDriftOptions::Validate() const {
  if (!(position_walk_m_per_sqrt_m >= 0)) return "position_walk_m_per_sqrt_m must be >= 0";
  if (!(yaw_walk_rad_per_sqrt_m >= 0)) return "yaw_walk_rad_per_sqrt_m must be >= 0";
  if (!(scale_error > -1)) return "scale_error must be > -1";
  if (!(position_jitter_m >= 0)) return "position_jitter_m must be >= 0";
  if (!(rotation_jitter_rad >= 0)) return "rotation_jitter_rad must be >= 0";
  return "";
}

Trajectory EmulateVioDrift(const Trajectory& ground_truth, const VioDriftOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  Random random(options.seed);
  const auto normal3 = [&random](double stddev) {
    return Eigen::Vector3d(random.Normal(0.0, stddev), random.Normal(0.0, stddev),
                           random.Normal(0.0, stddev));
  };
  Trajectory vio;
  vio.has_timestamps = ground_truth.has_timestamps;
  vio.poses.reserve(ground_truth.size());
  double yaw_drift = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < ground_truth.size(); ++k) {
    const Rigid3d& gt = ground_truth.poses[k].world_from_frame;
    if (k == 0) {
      position = gt.translation;
    } else {
      const Eigen::Vector3d step =
          gt.translation - ground_truth.poses[k - 1].world_from_frame.translation;
      const double distance = step.norm();
      yaw_drift += random.Normal(0.0, options.yaw_walk_rad_per_sqrt_m * std::sqrt(distance));
      position += Eigen::AngleAxisd(yaw_drift, Eigen::Vector3d::UnitZ()) *
                      ((1.0 + options.scale_error) * step) +
                  normal3(options.position_walk_m_per_sqrt_m * std::sqrt(distance));
    }
    const Eigen::Quaterniond drift_rotation(Eigen::AngleAxisd(yaw_drift, Eigen::Vector3d::UnitZ()));
    const Eigen::Vector3d jitter_angle = normal3(options.rotation_jitter_rad);
    Eigen::Quaterniond rotation = drift_rotation * gt.rotation;
    if (jitter_angle.norm() > 0) {
      rotation = rotation * Eigen::Quaterniond(
                                Eigen::AngleAxisd(jitter_angle.norm(), jitter_angle.normalized()));
    }
    vio.poses.push_back(
        {ground_truth.poses[k].timestamp_ns,
         Rigid3d(rotation.normalized(), position + normal3(options.position_jitter_m))});
  }
  return vio;
}

}  // namespace viosfm

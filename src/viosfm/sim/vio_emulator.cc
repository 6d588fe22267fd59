#include "viosfm/sim/vio_emulator.h"

#include <algorithm>
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

RealisticVioOptions RealisticVioOptions::Scaled(double factor) const {
  RealisticVioOptions scaled = *this;
  if (factor > 0.0) {
    scaled.model = model.Scaled(factor);
  } else {
    scaled.model = VioUncertaintyModel::Exact().Scaled(1e-9);
  }
  scaled.scale_error *= factor;
  return scaled;
}

std::string RealisticVioOptions::Validate() const {
  if (const std::string error = model.Validate(); !error.empty()) return "model." + error;
  if (!(scale_error > -1.0)) return "scale_error must be > -1";
  for (const double t : reinit_times_s) {
    if (!(t > 0.0) || !std::isfinite(t)) return "reinit_times_s must be > 0";
  }
  if (!(reinit_gap_s >= 0.0) || !std::isfinite(reinit_gap_s)) return "reinit_gap_s must be >= 0";
  return "";
}

EmulatedVio EmulateRealisticVio(const Trajectory& ground_truth,
                                const RealisticVioOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  const VioUncertaintyModel& m = options.model;
  Random random(options.seed);
  const auto normal3 = [&random](double stddev) {
    return Eigen::Vector3d(random.Normal(0.0, stddev), random.Normal(0.0, stddev),
                           random.Normal(0.0, stddev));
  };
  EmulatedVio vio;
  vio.world_from_frame.has_timestamps = ground_truth.has_timestamps;
  if (ground_truth.empty()) return vio;
  std::vector<timestamp_ns_t> reinit_ns;
  for (const double t : options.reinit_times_s) {
    reinit_ns.push_back(ground_truth.poses.front().timestamp_ns + SecondsToNs(t));
  }
  std::sort(reinit_ns.begin(), reinit_ns.end());
  const timestamp_ns_t gap_ns = SecondsToNs(options.reinit_gap_s);

  // The drift: VIO world from true world (rotation, and the VIO position of
  // the true body), accumulated step by step.
  Eigen::Quaterniond drift_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d position = ground_truth.poses.front().world_from_frame.translation;
  // Slowly varying frame noise (first-order Gauss-Markov, stationary).
  Eigen::Vector3d correlated_rotation = normal3(m.correlated_rotation_noise_rad);
  Eigen::Vector3d correlated_position = normal3(m.correlated_position_noise_m);
  int segment = 0;
  size_t next_reinit = 0;
  timestamp_ns_t restart_ns = -1;  // during a re-initialisation: when it ends
  bool restart_pending = false;
  for (size_t k = 0; k < ground_truth.size(); ++k) {
    const timestamp_ns_t t = ground_truth.poses[k].timestamp_ns;
    const Rigid3d& gt = ground_truth.poses[k].world_from_frame;
    if (next_reinit < reinit_ns.size() && t >= reinit_ns[next_reinit]) {
      ++next_reinit;
      restart_ns = t + gap_ns;
      restart_pending = true;
    }
    if (restart_pending) {
      if (t < restart_ns) continue;  // no pose while re-initialising
      // A new world frame: origin at the body, the body's yaw zero.
      restart_pending = false;
      ++segment;
      const Eigen::Vector3d forward = gt.rotation * Eigen::Vector3d::UnitX();
      const double yaw = std::atan2(forward.y(), forward.x());
      drift_rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()));
      position = Eigen::Vector3d::Zero();
    } else if (k > 0) {
      const Rigid3d& before = ground_truth.poses[k - 1].world_from_frame;
      const double dt = static_cast<double>(t - ground_truth.poses[k - 1].timestamp_ns) * 1e-9;
      const Eigen::Vector3d step = gt.translation - before.translation;
      const double distance = step.norm();
      const double turned = before.rotation.angularDistance(gt.rotation);
      const double tilt_sigma = m.tilt_per_sqrt_s * std::sqrt(dt);
      const double yaw_sigma = std::sqrt(m.yaw_per_sqrt_s * m.yaw_per_sqrt_s * dt +
                                         m.yaw_per_sqrt_m * m.yaw_per_sqrt_m * distance +
                                         m.yaw_per_sqrt_rad * m.yaw_per_sqrt_rad * turned);
      const Eigen::Vector3d drift_step(random.Normal(0.0, tilt_sigma),
                                       random.Normal(0.0, tilt_sigma),
                                       random.Normal(0.0, yaw_sigma));
      if (drift_step.norm() > 0.0) {
        drift_rotation =
            Eigen::Quaterniond(Eigen::AngleAxisd(drift_step.norm(), drift_step.normalized())) *
            drift_rotation;
      }
      const double walk_sigma = std::sqrt(m.position_per_sqrt_s * m.position_per_sqrt_s * dt +
                                          m.position_per_sqrt_m * m.position_per_sqrt_m * distance);
      position += drift_rotation * ((1.0 + options.scale_error) * step) + normal3(walk_sigma);
      const double rho = std::exp(-dt / m.noise_correlation_s);
      const double innovation = std::sqrt(std::max(0.0, 1.0 - rho * rho));
      correlated_rotation =
          rho * correlated_rotation + normal3(innovation * m.correlated_rotation_noise_rad);
      correlated_position =
          rho * correlated_position + normal3(innovation * m.correlated_position_noise_m);
    }
    const Eigen::Vector3d rotation_noise = normal3(m.rotation_noise_rad) + correlated_rotation;
    Eigen::Quaterniond rotation = drift_rotation * gt.rotation;
    if (rotation_noise.norm() > 0.0) {
      rotation = Eigen::Quaterniond(
                     Eigen::AngleAxisd(rotation_noise.norm(), rotation_noise.normalized())) *
                 rotation;
    }
    const Eigen::Vector3d noisy_position =
        position + normal3(m.position_noise_m) + correlated_position;
    vio.world_from_frame.poses.push_back({t, Rigid3d(rotation.normalized(), noisy_position)});
    vio.segments.push_back(segment);
  }
  return vio;
}

EmulatedVio EmulateRealisticVioOnGrid(const Trajectory& ground_truth,
                                      const RealisticVioOptions& options, double rate_hz) {
  VIOSFM_CHECK_GE(ground_truth.size(), 2u);
  VIOSFM_CHECK(rate_hz > 0.0 && std::isfinite(rate_hz));
  const double step_ns = 1e9 / rate_hz;
  Trajectory grid;
  grid.has_timestamps = ground_truth.has_timestamps;
  grid.poses.push_back(ground_truth.poses.front());
  for (size_t k = 1; k < ground_truth.size(); ++k) {
    const StampedPose& before = ground_truth.poses[k - 1];
    const StampedPose& after = ground_truth.poses[k];
    const timestamp_ns_t span = after.timestamp_ns - before.timestamp_ns;
    VIOSFM_CHECK_GT(span, 0);
    const int64_t steps =
        std::max<int64_t>(1, static_cast<int64_t>(std::ceil(static_cast<double>(span) / step_ns)));
    for (int64_t i = 1; i < steps; ++i) {
      const double s = static_cast<double>(i) / static_cast<double>(steps);
      Rigid3d pose;
      pose.rotation = before.world_from_frame.rotation.slerp(s, after.world_from_frame.rotation);
      pose.translation =
          (1.0 - s) * before.world_from_frame.translation + s * after.world_from_frame.translation;
      grid.poses.push_back(
          {before.timestamp_ns + static_cast<timestamp_ns_t>(std::llround(s * span)), pose});
    }
    grid.poses.push_back(after);
  }
  return EmulateRealisticVio(grid, options);
}

}  // namespace viosfm

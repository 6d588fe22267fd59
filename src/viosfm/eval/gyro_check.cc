#include "viosfm/eval/gyro_check.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// A longer gap between two gyro samples leaves an interval uncompared
// (the IMU dropped out there).
constexpr timestamp_ns_t kMaxGyroGapNs = 25'000'000;

// The gyro's rate at `t` (linear between the samples around it; `after`
// indexes the first sample at or after t).
Eigen::Vector3d RateAt(const std::vector<ImuSample>& imu, size_t after, timestamp_ns_t t) {
  if (imu[after].timestamp_ns == t || after == 0) return imu[after].gyro;
  const ImuSample& a = imu[after - 1];
  const ImuSample& b = imu[after];
  const double u = static_cast<double>(t - a.timestamp_ns) /
                   static_cast<double>(b.timestamp_ns - a.timestamp_ns);
  return (1.0 - u) * a.gyro + u * b.gyro;
}

// The gyro's samples between two stamps on the IMU's clock, the rates at
// the two ends interpolated; empty when the samples do not cover the
// stretch or leave a gap longer than kMaxGyroGapNs in it.
std::vector<ImuSample> GyroStretch(const std::vector<ImuSample>& imu, timestamp_ns_t from_ns,
                                   timestamp_ns_t to_ns) {
  if (imu.empty() || imu.front().timestamp_ns > from_ns || imu.back().timestamp_ns < to_ns) {
    return {};
  }
  const auto by_time = [](const ImuSample& sample, timestamp_ns_t t) {
    return sample.timestamp_ns < t;
  };
  size_t k =
      static_cast<size_t>(std::lower_bound(imu.begin(), imu.end(), from_ns, by_time) - imu.begin());
  std::vector<ImuSample> stretch;
  stretch.push_back({from_ns, RateAt(imu, k, from_ns), Eigen::Vector3d::Zero()});
  for (; k < imu.size() && imu[k].timestamp_ns < to_ns; ++k) {
    if (imu[k].timestamp_ns > from_ns) stretch.push_back(imu[k]);
  }
  stretch.push_back({to_ns, RateAt(imu, k, to_ns), Eigen::Vector3d::Zero()});
  for (size_t i = 1; i < stretch.size(); ++i) {
    if (stretch[i].timestamp_ns - stretch[i - 1].timestamp_ns > kMaxGyroGapNs) return {};
  }
  return stretch;
}

// body_from_body_end: the body's rotation over the stretch, the gyro's rate
// less `bias` integrated by the midpoint rule.
Eigen::Quaterniond IntegrateGyro(const std::vector<ImuSample>& stretch,
                                 const Eigen::Vector3d& bias) {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  for (size_t i = 1; i < stretch.size(); ++i) {
    const double dt =
        static_cast<double>(stretch[i].timestamp_ns - stretch[i - 1].timestamp_ns) * 1e-9;
    const Eigen::Vector3d rate = 0.5 * (stretch[i - 1].gyro + stretch[i].gyro) - bias;
    rotation = (rotation * So3Exp(rate * dt)).normalized();
  }
  return rotation;
}

// The bias minimising the sum over the stretches of the squared rotation
// vector between the gyro's rotation and the trajectory's, by Gauss-Newton
// from zero (Jacobian by central differences; the bias is small, the
// problem nearly linear).
Eigen::Vector3d FitGyroBias(const std::vector<const std::vector<ImuSample>*>& stretches,
                            const std::vector<Eigen::Quaterniond>& trajectory) {
  const auto residual = [&](size_t i, const Eigen::Vector3d& bias) {
    return QuaternionLog(
        (IntegrateGyro(*stretches[i], bias).conjugate() * trajectory[i]).normalized());
  };
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  constexpr double kStep = 1e-5;  // rad/s
  for (int iteration = 0; iteration < 5; ++iteration) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < stretches.size(); ++i) {
      const Eigen::Vector3d r = residual(i, bias);
      Eigen::Matrix3d jacobian;
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d step = kStep * Eigen::Vector3d::Unit(axis);
        jacobian.col(axis) = (residual(i, bias + step) - residual(i, bias - step)) / (2 * kStep);
      }
      normal += jacobian.transpose() * jacobian;
      rhs -= jacobian.transpose() * r;
    }
    const Eigen::Vector3d delta = normal.ldlt().solve(rhs);
    if (!delta.allFinite()) break;
    bias += delta;
    if (delta.norm() < 1e-9) break;
  }
  return bias;
}

}  // namespace

std::string GyroCheckOptions::Validate() const {
  if (!(interval_s > 0.0)) return "interval_s must be > 0";
  if (!(max_interval_factor >= 1.0)) return "max_interval_factor must be >= 1";
  return "";
}

namespace {

// An interval of the trajectory and the gyro's samples over it.
struct GyroInterval {
  size_t from;  // indices into world_from_cam.poses
  size_t to;
  std::vector<ImuSample> gyro;  // GyroStretch
};

// The trajectory's intervals, end to end, in time order; those across a gap
// or outside the IMU's samples counted in `result`.
std::vector<GyroInterval> GyroIntervals(const Trajectory& world_from_cam,
                                        const std::vector<ImuSample>& imu, const SensorRig& rig,
                                        const GyroCheckOptions& options, GyroCheckResult* result) {
  std::vector<size_t> order(world_from_cam.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return world_from_cam.poses[a].timestamp_ns < world_from_cam.poses[b].timestamp_ns;
  });

  // The intervals, end to end.
  const auto interval_ns = static_cast<timestamp_ns_t>(std::llround(options.interval_s * 1e9));
  const auto longest_ns = static_cast<timestamp_ns_t>(
      std::llround(options.interval_s * options.max_interval_factor * 1e9));
  std::vector<GyroInterval> intervals;
  size_t k = 0;
  while (k < order.size()) {
    const StampedPose& from = world_from_cam.poses[order[k]];
    size_t next = k + 1;
    while (next < order.size() &&
           world_from_cam.poses[order[next]].timestamp_ns - from.timestamp_ns < interval_ns) {
      ++next;
    }
    if (next == order.size()) break;
    const StampedPose& to = world_from_cam.poses[order[next]];
    if (to.timestamp_ns - from.timestamp_ns > longest_ns) {
      ++result->num_gaps;
    } else {
      std::vector<ImuSample> gyro =
          GyroStretch(imu, rig.CamToImuTime(from.timestamp_ns), rig.CamToImuTime(to.timestamp_ns));
      if (!gyro.empty()) {
        intervals.push_back({order[k], order[next], std::move(gyro)});
      } else {
        ++result->num_without_imu;
      }
    }
    k = next;
  }
  return intervals;
}

}  // namespace

GyroCheckResult CheckRotationsAgainstGyro(const Trajectory& world_from_cam,
                                          const std::vector<ImuSample>& imu, const SensorRig& rig,
                                          const GyroCheckOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("gyro check: " + error);
  }
  if (!world_from_cam.has_timestamps) {
    throw InputError("gyro check: the trajectory has no timestamps");
  }
  GyroCheckResult result;
  result.num_frames = world_from_cam.size();
  result.time_offset_ns = rig.cam_time_offset_ns;
  const std::vector<GyroInterval> intervals =
      GyroIntervals(world_from_cam, imu, rig, options, &result);
  if (intervals.empty()) {
    throw InputError("gyro check: no interval of " + std::to_string(options.interval_s) +
                     " s between the trajectory's " + std::to_string(world_from_cam.size()) +
                     " frames lies within the IMU's samples (" +
                     std::to_string(result.num_without_imu) + " outside them, " +
                     std::to_string(result.num_gaps) + " across gaps)");
  }

  const Eigen::Quaterniond cam_from_body = rig.body_from_cam.rotation.conjugate();
  const auto world_from_body = [&](size_t index) {
    return (world_from_cam.poses[index].world_from_frame.rotation * cam_from_body)
        .normalized()
        .toRotationMatrix();
  };
  // body_i_from_body_j from the trajectory, and its angle from the gyro's
  // at a bias.
  std::vector<Eigen::Quaterniond> trajectory_rotations;
  for (const GyroInterval& interval : intervals) {
    trajectory_rotations.emplace_back(world_from_body(interval.from).transpose() *
                                      world_from_body(interval.to));
  }
  const auto errors_at = [&](const Eigen::Vector3d& bias) {
    std::vector<double> errors;
    for (size_t i = 0; i < intervals.size(); ++i) {
      const Eigen::Quaterniond gyro = IntegrateGyro(intervals[i].gyro, bias);
      // The camera-IMU rotation turns the body's rotation error into the
      // camera's without changing its angle.
      errors.push_back(RotationAngleDeg(gyro.conjugate() * trajectory_rotations[i]));
    }
    return errors;
  };
  if (options.fit_bias) {
    // Fitted to every interval, then again to those within three times the
    // median error (and 0.05 degrees): a bend of the trajectory would
    // otherwise be spread over the whole recording as a bias.
    std::vector<bool> used(intervals.size(), true);
    for (int round = 0; round < 3; ++round) {
      std::vector<const std::vector<ImuSample>*> stretches;
      std::vector<Eigen::Quaterniond> rotations;
      for (size_t i = 0; i < intervals.size(); ++i) {
        if (!used[i]) continue;
        stretches.push_back(&intervals[i].gyro);
        rotations.push_back(trajectory_rotations[i]);
      }
      result.gyro_bias = FitGyroBias(stretches, rotations);
      result.num_bias_intervals = stretches.size();
      const std::vector<double> errors = errors_at(result.gyro_bias);
      std::vector<double> sorted = errors;
      std::nth_element(sorted.begin(), sorted.begin() + static_cast<ptrdiff_t>(sorted.size() / 2),
                       sorted.end());
      const double threshold = std::max(3.0 * sorted[sorted.size() / 2], 0.05);
      std::vector<bool> within(intervals.size());
      for (size_t i = 0; i < errors.size(); ++i) within[i] = errors[i] <= threshold;
      if (within == used) break;
      used = within;
    }
    result.bias_fitted = true;
  }

  const std::vector<double> errors = errors_at(result.gyro_bias);
  for (size_t i = 0; i < intervals.size(); ++i) {
    GyroCheckInterval checked;
    checked.from_ns = world_from_cam.poses[intervals[i].from].timestamp_ns;
    checked.to_ns = world_from_cam.poses[intervals[i].to].timestamp_ns;
    checked.gyro_angle_deg = RotationAngleDeg(IntegrateGyro(intervals[i].gyro, result.gyro_bias));
    checked.error_deg = errors[i];
    result.intervals.push_back(checked);
  }
  result.error_deg = ComputeErrorStatistics(errors);
  return result;
}

std::string FormatGyroCheck(const GyroCheckResult& result, size_t num_worst) {
  std::ostringstream out;
  out << std::fixed;
  const timestamp_ns_t start = result.intervals.front().from_ns;
  const auto seconds = [&](timestamp_ns_t t) { return static_cast<double>(t - start) * 1e-9; };
  double mean_length = 0.0;
  for (const GyroCheckInterval& interval : result.intervals) {
    mean_length += seconds(interval.to_ns) - seconds(interval.from_ns);
  }
  mean_length /= static_cast<double>(result.intervals.size());
  out << "rotations against the gyro: " << result.intervals.size() << " intervals of "
      << std::setprecision(2) << mean_length << " s on average between " << result.num_frames
      << " frames (" << result.num_without_imu << " not within the IMU's samples, "
      << result.num_gaps << " across gaps not compared), camera-IMU time offset "
      << std::setprecision(1) << static_cast<double>(result.time_offset_ns) * 1e-6 << " ms\n";
  out << "  gyro bias ";
  if (result.bias_fitted) {
    out << "fitted to " << result.num_bias_intervals << " of the intervals";
  } else {
    out << "zero (the raw gyro)";
  }
  out << ": [" << std::setprecision(5) << result.gyro_bias.x() << ", " << result.gyro_bias.y()
      << ", " << result.gyro_bias.z() << "] rad/s\n";
  const ErrorStatistics& s = result.error_deg;
  out << "  error (deg): rmse " << std::setprecision(3) << s.rmse << ", mean " << s.mean
      << ", median " << s.median << ", max " << s.max << "\n";
  std::vector<size_t> worst(result.intervals.size());
  std::iota(worst.begin(), worst.end(), size_t{0});
  std::stable_sort(worst.begin(), worst.end(), [&](size_t a, size_t b) {
    return result.intervals[a].error_deg > result.intervals[b].error_deg;
  });
  worst.resize(std::min(worst.size(), num_worst));
  for (const size_t index : worst) {
    const GyroCheckInterval& interval = result.intervals[index];
    out << "  " << std::setprecision(2) << seconds(interval.from_ns) << " to "
        << seconds(interval.to_ns) << " s: off by " << interval.error_deg << " deg (the gyro turns "
        << interval.gyro_angle_deg << " deg)\n";
  }
  return out.str();
}

}  // namespace viosfm

#include "viosfm/vio/imu_noise_check.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace viosfm {
namespace {

// Data-sheet ranges of MEMS IMUs, widened by ten for inflated configurations.
constexpr double kMinGyroDensity = 5e-5;   // rad/s/sqrt(Hz)
constexpr double kMaxGyroDensity = 1e-2;   // rad/s/sqrt(Hz)
constexpr double kMinAccelDensity = 5e-4;  // m/s^2/sqrt(Hz)
constexpr double kMaxAccelDensity = 5e-2;  // m/s^2/sqrt(Hz)
constexpr double kMinGyroWalk = 1e-7;      // rad/s^2/sqrt(Hz)
constexpr double kMaxGyroWalk = 1e-2;
constexpr double kMinAccelWalk = 1e-6;  // m/s^3/sqrt(Hz)
constexpr double kMaxAccelWalk = 1e-1;

std::string Number(double value) {
  std::ostringstream out;
  out << std::setprecision(3) << value;
  return out.str();
}

// Clamps *value into [low, high]; records a line when it changes.
void Bound(const std::string& name, const std::string& why, double low, double high, double* value,
           std::vector<std::string>* changes) {
  const double bounded = std::clamp(*value, low, high);
  if (bounded == *value) return;
  changes->push_back(name + " " + Number(*value) + " -> " + Number(bounded) + " (" + why + ")");
  *value = bounded;
}

}  // namespace

std::string ImuNoiseCheckOptions::Validate() const {
  if (!(min_ratio > 0.0) || !(min_ratio <= 1.0)) return "min_ratio must be in (0, 1]";
  if (!(max_ratio >= 1.0)) return "max_ratio must be >= 1";
  if (!(min_static_s > 0)) return "min_static_s must be > 0";
  if (!(motion_window_s > 0)) return "motion_window_s must be > 0";
  if (!(motion_span_s >= motion_window_s)) return "motion_span_s must be >= motion_window_s";
  return "";
}

std::pair<double, double> MeasureWhiteNoiseDensities(const std::vector<ImuSample>& imu,
                                                     timestamp_ns_t start_ns,
                                                     timestamp_ns_t end_ns) {
  const auto begin = std::lower_bound(
      imu.begin(), imu.end(), start_ns,
      [](const ImuSample& sample, timestamp_ns_t t) { return sample.timestamp_ns < t; });
  const auto end = std::upper_bound(
      imu.begin(), imu.end(), end_ns,
      [](timestamp_ns_t t, const ImuSample& sample) { return t < sample.timestamp_ns; });
  const long count = end - begin;
  if (count < 10) return {0.0, 0.0};
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero();
  for (auto it = begin; it != end; ++it) {
    gyro_mean += it->gyro;
    accel_mean += it->accel;
  }
  gyro_mean /= static_cast<double>(count);
  accel_mean /= static_cast<double>(count);
  Eigen::Vector3d gyro_var = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_var = Eigen::Vector3d::Zero();
  for (auto it = begin; it != end; ++it) {
    gyro_var += (it->gyro - gyro_mean).cwiseAbs2();
    accel_var += (it->accel - accel_mean).cwiseAbs2();
  }
  gyro_var /= static_cast<double>(count - 1);
  accel_var /= static_cast<double>(count - 1);
  const double dt =
      NsToSeconds((end - 1)->timestamp_ns - begin->timestamp_ns) / static_cast<double>(count - 1);
  const double root_dt = std::sqrt(dt);
  return {gyro_var.cwiseSqrt().mean() * root_dt, accel_var.cwiseSqrt().mean() * root_dt};
}

std::pair<timestamp_ns_t, std::pair<double, double>> QuietestWindowDensities(
    const std::vector<ImuSample>& imu, double window_s) {
  std::pair<timestamp_ns_t, std::pair<double, double>> quietest{0, {0.0, 0.0}};
  if (imu.size() < 10) return quietest;
  const timestamp_ns_t window_ns = SecondsToNs(window_s);
  const timestamp_ns_t step_ns = std::max<timestamp_ns_t>(1, window_ns / 4);
  for (timestamp_ns_t start = imu.front().timestamp_ns;
       start + window_ns <= imu.back().timestamp_ns; start += step_ns) {
    const std::pair<double, double> densities =
        MeasureWhiteNoiseDensities(imu, start, start + window_ns);
    if (densities.second <= 0.0) continue;
    if (quietest.second.second == 0.0 || densities.second < quietest.second.second) {
      quietest = {start, densities};
    }
  }
  return quietest;
}

std::pair<double, double> MeasureHighFrequencyDensities(const std::vector<ImuSample>& imu,
                                                        timestamp_ns_t start_ns,
                                                        timestamp_ns_t end_ns, double window_s) {
  const timestamp_ns_t window_ns = SecondsToNs(window_s);
  const auto by_time = [](const ImuSample& sample, timestamp_ns_t t) {
    return sample.timestamp_ns < t;
  };
  std::vector<double> gyro_densities;
  std::vector<double> accel_densities;
  for (timestamp_ns_t from = start_ns; window_ns > 0 && from + window_ns <= end_ns;
       from += window_ns) {
    const auto begin = std::lower_bound(imu.begin(), imu.end(), from, by_time);
    const auto end = std::lower_bound(begin, imu.end(), from + window_ns, by_time);
    if (end - begin < 10) continue;
    // Each reading against the line through its neighbours: for white noise
    // of standard deviation s per reading, the difference has variance
    // s^2 (1 + wa^2 + wb^2).
    Eigen::Vector3d gyro_sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d accel_sum = Eigen::Vector3d::Zero();
    double count = 0.0;
    for (auto it = begin + 1; it + 1 < end; ++it) {
      const double span = static_cast<double>((it + 1)->timestamp_ns - (it - 1)->timestamp_ns);
      if (!(span > 0.0)) continue;
      const double wa = static_cast<double>((it + 1)->timestamp_ns - it->timestamp_ns) / span;
      const double wb = 1.0 - wa;
      const double variance_factor = 1.0 + wa * wa + wb * wb;
      gyro_sum +=
          (it->gyro - wa * (it - 1)->gyro - wb * (it + 1)->gyro).cwiseAbs2() / variance_factor;
      accel_sum +=
          (it->accel - wa * (it - 1)->accel - wb * (it + 1)->accel).cwiseAbs2() / variance_factor;
      count += 1.0;
    }
    const double dt = NsToSeconds((end - 1)->timestamp_ns - begin->timestamp_ns) /
                      static_cast<double>(end - begin - 1);
    const double root_dt = std::sqrt(dt);
    gyro_densities.push_back((gyro_sum / count).cwiseSqrt().mean() * root_dt);
    accel_densities.push_back((accel_sum / count).cwiseSqrt().mean() * root_dt);
  }
  if (gyro_densities.empty()) return {0.0, 0.0};
  const auto median = [](std::vector<double>* values) {
    const size_t middle = values->size() / 2;
    std::nth_element(values->begin(), values->begin() + middle, values->end());
    double value = (*values)[middle];
    if (values->size() % 2 == 0) {
      value = 0.5 * (value + *std::max_element(values->begin(), values->begin() + middle));
    }
    return value;
  };
  return {median(&gyro_densities), median(&accel_densities)};
}

namespace {

// The check's one line: what it found and what it changed.
std::string DescribeCheck(const ImuNoiseCheck& check, const StaticInitResult* static_interval) {
  std::ostringstream message;
  message << "IMU noise: ";
  if (check.measured) {
    message << "white noise measured at rest over "
            << Number(NsToSeconds(static_interval->end_ns - static_interval->start_ns))
            << " s: gyro " << Number(check.measured_gyro_density) << " rad/s/sqrt(Hz), accel "
            << Number(check.measured_accel_density) << " m/s^2/sqrt(Hz); ";
  }
  if (check.motion_gyro_density > 0.0) {
    message << "in motion: gyro " << Number(check.motion_gyro_density) << ", accel "
            << Number(check.motion_accel_density) << "; ";
  }
  if (check.changes.empty()) {
    message << "the calibration's figures are used";
  } else {
    message << "changed ";
    for (size_t i = 0; i < check.changes.size(); ++i) {
      message << (i > 0 ? "; " : "") << check.changes[i];
    }
  }
  return message.str();
}

}  // namespace

ImuNoiseCheck CheckImuNoise(const ImuNoise& given, const std::vector<ImuSample>& imu,
                            const StaticInitResult* static_interval,
                            const ImuNoiseCheckOptions& options, timestamp_ns_t motion_start_ns,
                            timestamp_ns_t motion_end_ns) {
  ImuNoiseCheck check;
  check.given = given;
  check.used = given;
  if (!options.enabled) {
    check.message = "IMU noise: the calibration's figures, unchecked";
    return check;
  }
  ImuNoise& used = check.used;
  if (static_interval != nullptr && static_interval->is_static() &&
      NsToSeconds(static_interval->end_ns - static_interval->start_ns) >= options.min_static_s) {
    const auto [gyro, accel] =
        MeasureWhiteNoiseDensities(imu, static_interval->start_ns, static_interval->end_ns);
    if (gyro > 0.0 && accel > 0.0) {
      check.measured = true;
      check.measured_gyro_density = gyro;
      check.measured_accel_density = accel;
      const std::string why = "the calibration may state " + Number(options.min_ratio) + " to " +
                              Number(options.max_ratio) + " times the density measured at rest";
      Bound("gyroscope_noise_density", why, options.min_ratio * gyro, options.max_ratio * gyro,
            &used.gyro_noise_density, &check.changes);
      Bound("accelerometer_noise_density", why, options.min_ratio * accel,
            options.max_ratio * accel, &used.accel_noise_density, &check.changes);
    }
  }
  if (!check.measured) {
    const std::string why = "outside the range of MEMS IMUs";
    Bound("gyroscope_noise_density", why, kMinGyroDensity, kMaxGyroDensity,
          &used.gyro_noise_density, &check.changes);
    Bound("accelerometer_noise_density", why, kMinAccelDensity, kMaxAccelDensity,
          &used.accel_noise_density, &check.changes);
    // The quietest stretch of the stream bounds the white noise from above.
    const auto [start_ns, densities] = QuietestWindowDensities(imu, options.min_static_s);
    if (densities.first > 0.0 && densities.second > 0.0) {
      check.bound_start_ns = start_ns;
      check.bound_gyro_density = densities.first;
      check.bound_accel_density = densities.second;
      const std::string bound_why =
          "above the spread of the quietest " + Number(options.min_static_s) + " s of the IMU, " +
          FormatNsAsSeconds(start_ns - imu.front().timestamp_ns, 2) + " s after its first sample";
      Bound("gyroscope_noise_density", bound_why, kMinGyroDensity,
            std::max(kMinGyroDensity, densities.first), &used.gyro_noise_density, &check.changes);
      Bound("accelerometer_noise_density", bound_why, kMinAccelDensity,
            std::max(kMinAccelDensity, densities.second), &used.accel_noise_density,
            &check.changes);
    }
  }
  if (options.check_in_motion && !imu.empty()) {
    // The high-frequency content in motion bounds the densities from below.
    timestamp_ns_t from = std::max(motion_start_ns, imu.front().timestamp_ns);
    if (static_interval != nullptr && static_interval->is_static()) {
      from = std::max(from, static_interval->end_ns);
    }
    const timestamp_ns_t to = std::min(
        {from + SecondsToNs(options.motion_span_s), motion_end_ns, imu.back().timestamp_ns});
    const auto [gyro, accel] =
        MeasureHighFrequencyDensities(imu, from, to, options.motion_window_s);
    check.motion_gyro_density = gyro;
    check.motion_accel_density = accel;
    if (gyro > 0.0 && accel > 0.0) {
      const std::string why = "below " + Number(options.min_ratio) +
                              " times the high-frequency content measured in motion over " +
                              Number(NsToSeconds(to - from)) + " s (vibration)";
      Bound("gyroscope_noise_density", why, options.min_ratio * gyro,
            std::max(used.gyro_noise_density, options.min_ratio * gyro), &used.gyro_noise_density,
            &check.changes);
      Bound("accelerometer_noise_density", why, options.min_ratio * accel,
            std::max(used.accel_noise_density, options.min_ratio * accel),
            &used.accel_noise_density, &check.changes);
    }
  }
  if (options.scale_random_walks) {
    // A calibration's figures for one sensor come from one source (an Allan
    // variance, a data sheet, a factor applied to both): a white-noise
    // density found wrong by a factor makes the same factor likely for the
    // random walk, which a few seconds at rest cannot measure.
    const auto scale_walk = [&](const std::string& name, double given_density, double used_density,
                                double* walk) {
      if (used_density == given_density || !(given_density > 0.0)) return;
      const double scaled = *walk * (used_density / given_density);
      check.changes.push_back(name + " " + Number(*walk) + " -> " + Number(scaled) +
                              " (scaled as its white-noise density)");
      *walk = scaled;
    };
    scale_walk("gyroscope_random_walk", given.gyro_noise_density, used.gyro_noise_density,
               &used.gyro_random_walk);
    scale_walk("accelerometer_random_walk", given.accel_noise_density, used.accel_noise_density,
               &used.accel_random_walk);
  }
  const std::string why = "outside the range of MEMS IMUs";
  Bound("gyroscope_random_walk", why, kMinGyroWalk, kMaxGyroWalk, &used.gyro_random_walk,
        &check.changes);
  Bound("accelerometer_random_walk", why, kMinAccelWalk, kMaxAccelWalk, &used.accel_random_walk,
        &check.changes);

  check.message = DescribeCheck(check, static_interval);
  return check;
}

}  // namespace viosfm

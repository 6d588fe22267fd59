#include "viosfm/vio/static_init.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

struct WindowStats {
  Eigen::Vector3d mean_accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_gyro = Eigen::Vector3d::Zero();
  double accel_stddev = 0.0;
  double gyro_stddev = 0.0;
  int num_samples = 0;
};

// Statistics of samples[begin, end): the means, and the RMS deviation from
// them of the means over consecutive blocks of smoothing_ns (weighted by
// their sample counts), which averages out high-frequency vibration.
WindowStats ComputeStats(const std::vector<ImuSample>& samples, size_t begin, size_t end,
                         timestamp_ns_t smoothing_ns) {
  VIOSFM_CHECK_LT(begin, end);
  WindowStats stats;
  stats.num_samples = static_cast<int>(end - begin);
  for (size_t k = begin; k < end; ++k) {
    stats.mean_accel += samples[k].accel;
    stats.mean_gyro += samples[k].gyro;
  }
  stats.mean_accel /= stats.num_samples;
  stats.mean_gyro /= stats.num_samples;
  double accel_sq = 0.0;
  double gyro_sq = 0.0;
  const timestamp_ns_t origin = samples[begin].timestamp_ns;
  size_t k = begin;
  while (k < end) {
    const int64_t block = (samples[k].timestamp_ns - origin) / smoothing_ns;
    Eigen::Vector3d accel_sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d gyro_sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (; k < end && (samples[k].timestamp_ns - origin) / smoothing_ns == block; ++k) {
      accel_sum += samples[k].accel;
      gyro_sum += samples[k].gyro;
      ++count;
    }
    accel_sq += count * (accel_sum / count - stats.mean_accel).squaredNorm();
    gyro_sq += count * (gyro_sum / count - stats.mean_gyro).squaredNorm();
  }
  stats.accel_stddev = std::sqrt(accel_sq / stats.num_samples);
  stats.gyro_stddev = std::sqrt(gyro_sq / stats.num_samples);
  return stats;
}

bool IsStatic(const WindowStats& stats, const StaticInitOptions& options) {
  return stats.accel_stddev <= options.max_accel_stddev &&
         stats.gyro_stddev <= options.max_gyro_stddev &&
         stats.mean_gyro.norm() <= options.max_gyro_norm &&
         std::abs(stats.mean_accel.norm() - options.gravity_magnitude) <=
             options.max_gravity_norm_error;
}

std::string DescribeStats(const WindowStats& stats) {
  std::ostringstream out;
  out << "smoothed accel stddev " << stats.accel_stddev << " m/s^2, gyro stddev "
      << stats.gyro_stddev << " rad/s, mean gyro norm " << stats.mean_gyro.norm()
      << " rad/s, mean accel norm " << stats.mean_accel.norm() << " m/s^2 over "
      << stats.num_samples << " samples";
  return out.str();
}

// Index of the first sample with stamp >= t.
size_t LowerIndex(const std::vector<ImuSample>& samples, timestamp_ns_t t) {
  return std::lower_bound(
             samples.begin(), samples.end(), t,
             [](const ImuSample& s, timestamp_ns_t value) { return s.timestamp_ns < value; }) -
         samples.begin();
}

// Index one past the last sample with stamp <= t.
size_t UpperIndex(const std::vector<ImuSample>& samples, timestamp_ns_t t) {
  return std::upper_bound(
             samples.begin(), samples.end(), t,
             [](timestamp_ns_t value, const ImuSample& s) { return value < s.timestamp_ns; }) -
         samples.begin();
}

// The longest interval between consecutive samples of samples[begin, end);
// infinite for fewer than two samples.
timestamp_ns_t LongestInterval(const std::vector<ImuSample>& samples, size_t begin, size_t end) {
  if (end < begin + 2) return std::numeric_limits<timestamp_ns_t>::max();
  timestamp_ns_t longest = 0;
  for (size_t k = begin + 1; k < end; ++k) {
    longest = std::max(longest, samples[k].timestamp_ns - samples[k - 1].timestamp_ns);
  }
  return longest;
}

}  // namespace

std::string StaticInitOptions::Validate() const {
  if (!(window_s > 0)) return "window_s must be > 0";
  if (!(step_s > 0 && step_s <= window_s)) return "step_s must be in (0, window_s]";
  if (!(smoothing_s > 0 && smoothing_s <= window_s)) return "smoothing_s must be in (0, window_s]";
  if (!(max_accel_stddev > 0)) return "max_accel_stddev must be > 0";
  if (!(max_gyro_stddev > 0)) return "max_gyro_stddev must be > 0";
  if (!(max_gyro_norm > 0)) return "max_gyro_norm must be > 0";
  if (!(motion_margin_s >= 0)) return "motion_margin_s must be >= 0";
  if (!(min_static_s > 0)) return "min_static_s must be > 0";
  if (!(lookback_s >= 0)) return "lookback_s must be >= 0";
  if (!(max_propagation_s >= 0)) return "max_propagation_s must be >= 0";
  if (!(max_gravity_norm_error > 0)) return "max_gravity_norm_error must be > 0";
  if (!(gravity_magnitude > 0)) return "gravity_magnitude must be > 0";
  return "";
}

const char* StaticInitStatusName(StaticInitStatus status) {
  switch (status) {
    case StaticInitStatus::kStatic: return "static";
    case StaticInitStatus::kNotStatic: return "not static";
    case StaticInitStatus::kNotEnoughData: return "not enough IMU data";
  }
  return "unknown";
}

Eigen::Quaterniond GravityAlignedRotation(const Eigen::Vector3d& up_in_body, double* roll_rad,
                                          double* pitch_rad) {
  VIOSFM_CHECK_GT(up_in_body.norm(), 0.0);
  const Eigen::Vector3d u = up_in_body.normalized();
  // Ry(pitch) Rx(roll) maps u to +z iff
  // u = (-sin(pitch), sin(roll) cos(pitch), cos(roll) cos(pitch)).
  const double roll = std::atan2(u.y(), u.z());
  const double pitch = std::atan2(-u.x(), std::hypot(u.y(), u.z()));
  if (roll_rad != nullptr) *roll_rad = roll;
  if (pitch_rad != nullptr) *pitch_rad = pitch;
  return Eigen::Quaterniond(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

StaticInitResult DetectStaticStart(const std::vector<ImuSample>& samples, timestamp_ns_t from,
                                   timestamp_ns_t to, const StaticInitOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  StaticInitResult result;
  const size_t first = LowerIndex(samples, from);
  const size_t last_end = UpperIndex(samples, to);
  const timestamp_ns_t window_ns = SecondsToNs(options.window_s);
  const timestamp_ns_t step_ns = std::max<timestamp_ns_t>(1, SecondsToNs(options.step_s));
  const timestamp_ns_t smoothing_ns = std::max<timestamp_ns_t>(1, SecondsToNs(options.smoothing_s));
  if (first + 2 > last_end ||
      samples[last_end - 1].timestamp_ns - samples[first].timestamp_ns < window_ns) {
    result.status = StaticInitStatus::kNotEnoughData;
    result.message = "less than window_s of IMU samples in the range";
    return result;
  }
  const timestamp_ns_t t_first = samples[first].timestamp_ns;
  const timestamp_ns_t t_last = samples[last_end - 1].timestamp_ns;

  // Slide the window; the last window is aligned with the last sample so
  // that a fully static range is detected as a whole.
  timestamp_ns_t static_end = t_first;
  bool ended_by_motion = false;
  for (timestamp_ns_t start = t_first;; start += step_ns) {
    const timestamp_ns_t window_start = std::min(start, t_last - window_ns);
    const size_t begin = LowerIndex(samples, window_start);
    const size_t end = UpperIndex(samples, window_start + window_ns);
    // An IMU gap longer than the smoothing blocks ends the static start: what
    // the body did while the IMU was silent is unknown. The samples on
    // either side of the window count, so that a gap at its edge is seen.
    if (LongestInterval(samples, begin > 0 ? begin - 1 : 0, std::min(end + 1, samples.size())) >
        smoothing_ns) {
      if (start == t_first) {
        result.status = StaticInitStatus::kNotStatic;
        result.message = "the IMU has a gap longer than smoothing_s in the first window";
        return result;
      }
      ended_by_motion = true;
      break;
    }
    const WindowStats stats = ComputeStats(samples, begin, end, smoothing_ns);
    if (!IsStatic(stats, options)) {
      if (start == t_first) {
        result.status = StaticInitStatus::kNotStatic;
        result.message = "first window moves: " + DescribeStats(stats);
        return result;
      }
      ended_by_motion = true;
      break;
    }
    static_end = samples[end - 1].timestamp_ns;
    if (window_start + window_ns >= t_last) break;
  }

  if (ended_by_motion) {
    static_end -= SecondsToNs(options.motion_margin_s);
    if (static_end - t_first < SecondsToNs(options.min_static_s)) {
      result.status = StaticInitStatus::kNotStatic;
      result.message = "static for less than min_static_s + motion_margin_s";
      return result;
    }
  }
  const size_t end = UpperIndex(samples, static_end);
  static_end = samples[end - 1].timestamp_ns;
  const WindowStats stats = ComputeStats(samples, first, end, smoothing_ns);
  result.status = StaticInitStatus::kStatic;
  result.start_ns = t_first;
  result.end_ns = static_end;
  result.num_samples = stats.num_samples;
  result.accel_stddev = stats.accel_stddev;
  result.gyro_stddev = stats.gyro_stddev;
  result.up_in_body = stats.mean_accel.normalized();
  result.gravity_in_body = -options.gravity_magnitude * result.up_in_body;
  result.world_from_body =
      Rigid3d(GravityAlignedRotation(result.up_in_body, &result.roll_rad, &result.pitch_rad),
              Eigen::Vector3d::Zero());
  result.gyro_bias = stats.mean_gyro;
  if (options.estimate_accel_bias_along_gravity) {
    result.accel_bias = (stats.mean_accel.norm() - options.gravity_magnitude) * result.up_in_body;
  }
  result.message = DescribeStats(stats);
  return result;
}

}  // namespace viosfm

#include "viosfm/pipeline/frame_selection.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

struct Window {
  timestamp_ns_t begin = 0;
  timestamp_ns_t end = 0;
};

// The window of length `length` ending at `t`, moved to start at the first
// sample when it would begin before it.
Window TrailingWindow(timestamp_ns_t t, timestamp_ns_t length, timestamp_ns_t data_begin) {
  if (t - length < data_begin) return {data_begin, data_begin + length};
  return {t - length, t};
}

// Indices [first, last) of the sorted `times` inside [window.begin, window.end].
std::pair<size_t, size_t> SamplesIn(const std::vector<timestamp_ns_t>& times, const Window& w) {
  const auto first = std::lower_bound(times.begin(), times.end(), w.begin);
  const auto last = std::upper_bound(first, times.end(), w.end);
  return {static_cast<size_t>(first - times.begin()), static_cast<size_t>(last - times.begin())};
}

// Enough data in the window: at least 2 samples spanning half of it.
bool Covered(const std::vector<timestamp_ns_t>& times, size_t first, size_t last,
             timestamp_ns_t length) {
  return last >= first + 2 && 2 * (times[last - 1] - times[first]) >= length;
}

// Low-passed IMU (gyro, accel) with prefix sums for window statistics.
class ImuSignal {
 public:
  ImuSignal(std::vector<timestamp_ns_t> times, std::vector<Vector6d> values)
      : times_(std::move(times)), values_(std::move(values)) {
    // Sums of the values minus the first one, so that the squares stay small.
    offset_ = values_.empty() ? Vector6d::Zero() : values_.front();
    sum_.assign(values_.size() + 1, Vector6d::Zero());
    sum_sq_.assign(values_.size() + 1, Vector6d::Zero());
    for (size_t i = 0; i < values_.size(); ++i) {
      const Vector6d v = values_[i] - offset_;
      sum_[i + 1] = sum_[i] + v;
      sum_sq_[i + 1] = sum_sq_[i] + v.cwiseProduct(v);
    }
  }

  // The reversed signal with negated times: the end of the sequence as a start.
  ImuSignal Mirrored() const {
    std::vector<timestamp_ns_t> times(times_.rbegin(), times_.rend());
    for (timestamp_ns_t& t : times) t = -t;
    return ImuSignal(std::move(times), std::vector<Vector6d>(values_.rbegin(), values_.rend()));
  }

  bool empty() const { return times_.empty(); }
  timestamp_ns_t begin() const { return times_.front(); }
  const std::vector<timestamp_ns_t>& times() const { return times_; }
  const std::vector<Vector6d>& values() const { return values_; }

  // Mean of the samples in [first, last).
  Vector6d Mean(size_t first, size_t last) const {
    return (sum_[last] - sum_[first]) / static_cast<double>(last - first) + offset_;
  }

  // nullopt if the window has too little data.
  std::optional<bool> WindowStatic(const Window& window, timestamp_ns_t length,
                                   const FrameSelectionOptions& options) const {
    const auto [first, last] = SamplesIn(times_, window);
    if (!Covered(times_, first, last, length)) return std::nullopt;
    const double n = static_cast<double>(last - first);
    const Vector6d mean = (sum_[last] - sum_[first]) / n;
    const Vector6d variance =
        ((sum_sq_[last] - sum_sq_[first]) / n - mean.cwiseProduct(mean)).cwiseMax(0.0);
    const double gyro_spread = std::sqrt(variance.head<3>().sum());
    const double accel_spread = std::sqrt(variance.tail<3>().sum());
    const double gyro_mean = (mean + offset_).head<3>().norm();
    return gyro_spread <= options.max_static_gyro_stddev_rad_s &&
           accel_spread <= options.max_static_accel_stddev_m_s2 &&
           gyro_mean <= options.max_static_gyro_mean_rad_s;
  }

 private:
  std::vector<timestamp_ns_t> times_;
  std::vector<Vector6d> values_;
  Vector6d offset_;
  std::vector<Vector6d> sum_;
  std::vector<Vector6d> sum_sq_;
};

// Centred moving average of gyro and accel over `length` ns.
ImuSignal LowPassImu(const ImuSamples& imu, timestamp_ns_t length) {
  std::vector<timestamp_ns_t> times(imu.size());
  std::vector<Vector6d> raw(imu.size());
  for (size_t i = 0; i < imu.size(); ++i) {
    times[i] = imu[i].timestamp_ns;
    raw[i] << imu[i].gyro, imu[i].accel;
  }
  const ImuSignal raw_signal(times, raw);
  std::vector<Vector6d> smooth(imu.size());
  for (size_t i = 0; i < imu.size(); ++i) {
    const auto [first, last] = SamplesIn(times, {times[i] - length / 2, times[i] + length / 2});
    smooth[i] = raw_signal.Mean(first, last);
  }
  return ImuSignal(std::move(times), std::move(smooth));
}

class PoseSignal {
 public:
  PoseSignal(std::vector<timestamp_ns_t> times, std::vector<Rigid3d> poses)
      : times_(std::move(times)), poses_(std::move(poses)) {}

  explicit PoseSignal(const Trajectory& trajectory) {
    for (const StampedPose& pose : trajectory.poses) {
      // Repeated stamps: the first pose is kept.
      if (!times_.empty() && pose.timestamp_ns <= times_.back()) continue;
      times_.push_back(pose.timestamp_ns);
      poses_.push_back(pose.world_from_frame);
    }
  }

  PoseSignal Mirrored() const {
    std::vector<timestamp_ns_t> times(times_.rbegin(), times_.rend());
    for (timestamp_ns_t& t : times) t = -t;
    return PoseSignal(std::move(times), std::vector<Rigid3d>(poses_.rbegin(), poses_.rend()));
  }

  bool empty() const { return times_.empty(); }
  timestamp_ns_t begin() const { return times_.front(); }

  std::optional<bool> WindowStatic(const Window& window, timestamp_ns_t length,
                                   const FrameSelectionOptions& options) const {
    const auto [first, last] = SamplesIn(times_, window);
    if (!Covered(times_, first, last, length)) return std::nullopt;
    const Rigid3d& reference = poses_[first];
    for (size_t i = first + 1; i < last; ++i) {
      if ((poses_[i].translation - reference.translation).norm() >
              options.max_static_translation_m ||
          poses_[i].rotation.angularDistance(reference.rotation) >
              options.max_static_rotation_rad) {
        return false;
      }
    }
    return true;
  }

 private:
  std::vector<timestamp_ns_t> times_;
  std::vector<Rigid3d> poses_;
};

// Static tests for one direction of time (the start; the end is the start
// of the mirrored signals).
class StaticDetector {
 public:
  StaticDetector(const ImuSignal* imu, const PoseSignal* poses,
                 const FrameSelectionOptions& options)
      : imu_(imu),
        poses_(poses),
        options_(options),
        length_(SecondsToNs(options.static_window_s)) {}

  // Whether the window ending at image time t is static by every source;
  // a source without data there says "moving".
  bool IsStatic(timestamp_ns_t t) const {
    if (imu_ != nullptr) {
      const std::optional<bool> is_static =
          imu_->WindowStatic(TrailingWindow(t, length_, imu_->begin()), length_, options_);
      if (!is_static.value_or(false)) return false;
    }
    if (poses_ != nullptr) {
      const std::optional<bool> is_static =
          poses_->WindowStatic(TrailingWindow(t, length_, poses_->begin()), length_, options_);
      if (!is_static.value_or(false)) return false;
    }
    return true;
  }

  // Where the low-passed IMU left the static reference (the mean of the
  // static window ending at t_static) before t_moving: the earliest sample of
  // the last run of deviating samples. nullopt without IMU or deviation.
  std::optional<timestamp_ns_t> RefineOnset(timestamp_ns_t t_static,
                                            timestamp_ns_t t_moving) const {
    if (imu_ == nullptr) return std::nullopt;
    const Window reference = TrailingWindow(t_static, length_, imu_->begin());
    const auto [ref_first, ref_last] = SamplesIn(imu_->times(), reference);
    if (ref_last <= ref_first) return std::nullopt;
    const Vector6d mean = imu_->Mean(ref_first, ref_last);
    const auto [first, last] = SamplesIn(imu_->times(), {reference.begin, t_moving});
    auto deviates = [&](size_t i) {
      const Vector6d delta = imu_->values()[i] - mean;
      return delta.head<3>().norm() > options_.max_static_gyro_stddev_rad_s ||
             delta.tail<3>().norm() > options_.max_static_accel_stddev_m_s2;
    };
    size_t i = last;
    while (i > first && !deviates(i - 1)) --i;
    if (i == first) return std::nullopt;
    while (i > first && deviates(i - 1)) --i;
    return imu_->times()[i];
  }

 private:
  const ImuSignal* imu_;
  const PoseSignal* poses_;
  const FrameSelectionOptions& options_;
  timestamp_ns_t length_;
};

struct StartTrim {
  bool moving = false;    // some image's window is not static
  size_t first_kept = 0;  // first image at or after the motion start
  timestamp_ns_t onset = 0;
};

StartTrim TrimStart(const std::vector<timestamp_ns_t>& image_times,
                    const StaticDetector& detector) {
  for (size_t k = 0; k < image_times.size(); ++k) {
    if (detector.IsStatic(image_times[k])) continue;
    if (k == 0) return {true, 0, image_times[0]};
    const timestamp_ns_t onset =
        std::min(image_times[k],
                 detector.RefineOnset(image_times[k - 1], image_times[k]).value_or(image_times[k]));
    const size_t first =
        static_cast<size_t>(std::lower_bound(image_times.begin(), image_times.begin() + k, onset) -
                            image_times.begin());
    return {true, first, onset};
  }
  return {};
}

// Indices in [first, last] kept at `rate_hz`: the frame nearest to each
// point of the grid first_time + m / rate_hz.
std::vector<size_t> Downsample(const std::vector<timestamp_ns_t>& times, size_t first, size_t last,
                               double rate_hz) {
  std::vector<size_t> kept;
  const timestamp_ns_t period = SecondsToNs(1.0 / rate_hz);
  const auto begin = times.begin() + static_cast<std::ptrdiff_t>(first);
  const auto end = times.begin() + static_cast<std::ptrdiff_t>(last) + 1;
  for (timestamp_ns_t grid = times[first]; grid <= times[last]; grid += period) {
    auto it = std::lower_bound(begin, end, grid);
    if (it == end || (it != begin && grid - *(it - 1) <= *it - grid)) --it;
    const auto index = static_cast<size_t>(it - times.begin());
    if (kept.empty() || kept.back() != index) kept.push_back(index);
  }
  return kept;
}

}  // namespace

StaticSource ParseStaticSource(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "auto") return StaticSource::kAuto;
  if (lower == "imu") return StaticSource::kImu;
  if (lower == "trajectory") return StaticSource::kTrajectory;
  if (lower == "imu_and_trajectory") return StaticSource::kImuAndTrajectory;
  throw InputError("unknown static source '" + name +
                   "': expected auto, imu, trajectory or imu_and_trajectory");
}

std::string StaticSourceName(StaticSource source) {
  switch (source) {
    case StaticSource::kAuto: return "auto";
    case StaticSource::kImu: return "imu";
    case StaticSource::kTrajectory: return "trajectory";
    case StaticSource::kImuAndTrajectory: return "imu_and_trajectory";
  }
  return "unknown";
}

std::string FrameDecisionName(FrameDecision decision) {
  switch (decision) {
    case FrameDecision::kKept: return "kept";
    case FrameDecision::kStaticStart: return "static_start";
    case FrameDecision::kStaticEnd: return "static_end";
    case FrameDecision::kStatic: return "static";
    case FrameDecision::kDownsampled: return "downsampled";
  }
  return "unknown";
}

std::string FrameSelectionOptions::Validate() const {
  auto positive = [](double value) { return value > 0.0 && std::isfinite(value); };
  if (!positive(static_window_s)) return "static_window_s must be positive";
  if (!positive(imu_lowpass_s)) return "imu_lowpass_s must be positive";
  if (!positive(max_static_gyro_stddev_rad_s))
    return "max_static_gyro_stddev_rad_s must be positive";
  if (!positive(max_static_gyro_mean_rad_s)) return "max_static_gyro_mean_rad_s must be positive";
  if (!positive(max_static_accel_stddev_m_s2))
    return "max_static_accel_stddev_m_s2 must be positive";
  if (!positive(max_static_translation_m)) return "max_static_translation_m must be positive";
  if (!positive(max_static_rotation_rad)) return "max_static_rotation_rad must be positive";
  if (!(target_rate_hz >= 0.0 && std::isfinite(target_rate_hz))) {
    return "target_rate_hz must be 0 (keep all) or positive";
  }
  return "";
}

size_t FrameSelection::Count(FrameDecision decision) const {
  return static_cast<size_t>(std::count(decisions.begin(), decisions.end(), decision));
}

bool FrameSelectionUsesTrajectory(const Sequence& sequence, const FrameSelectionOptions& options) {
  if (!options.trim_static) return false;
  switch (options.static_source) {
    case StaticSource::kAuto: return !sequence.has_imu();
    case StaticSource::kImu: return false;
    case StaticSource::kTrajectory:
    case StaticSource::kImuAndTrajectory: return true;
  }
  return true;
}

FrameSelection SelectFrames(const Sequence& sequence, const FrameSelectionOptions& options,
                            const Trajectory* trajectory) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("frame selection options: " + error);
  }
  FrameSelection selection;
  const size_t num_images = sequence.images.size();
  if (num_images == 0) {
    selection.status = FrameSelectionStatus::kNoImages;
    selection.message = "no images";
    return selection;
  }
  std::vector<timestamp_ns_t> times(num_images);
  for (size_t k = 0; k < num_images; ++k) times[k] = sequence.images[k].timestamp_ns;
  for (size_t k = 1; k < num_images; ++k) {
    VIOSFM_CHECK_GT(times[k], times[k - 1]) << "images must be in increasing time";
  }

  size_t first_kept = 0;
  size_t last_kept = num_images - 1;
  selection.motion_start_ns = times.front();
  selection.motion_end_ns = times.back();
  if (options.trim_static) {
    const bool has_trajectory = trajectory != nullptr || sequence.has_ground_truth();
    bool use_imu = false;
    bool use_trajectory = false;
    switch (options.static_source) {
      case StaticSource::kAuto:
        use_imu = sequence.has_imu();
        use_trajectory = !use_imu && has_trajectory;
        break;
      case StaticSource::kImu: use_imu = true; break;
      case StaticSource::kTrajectory: use_trajectory = true; break;
      case StaticSource::kImuAndTrajectory: use_imu = use_trajectory = true; break;
    }
    if (use_imu && !sequence.has_imu()) {
      throw InputError("frame selection: static source '" +
                       StaticSourceName(options.static_source) + "' needs an IMU, and " +
                       sequence.root.string() + " has none");
    }
    if (use_trajectory && !has_trajectory) {
      throw InputError("frame selection: static source '" +
                       StaticSourceName(options.static_source) +
                       "' needs a trajectory or ground truth, and none was given");
    }
    std::optional<ImuSignal> imu;
    std::optional<PoseSignal> poses;
    if (use_imu) imu = LowPassImu(sequence.imu, SecondsToNs(options.imu_lowpass_s));
    if (use_trajectory) {
      poses = PoseSignal(trajectory != nullptr ? *trajectory : GroundTruthBodyTrajectory(sequence));
      if (poses->empty()) throw InputError("frame selection: the trajectory is empty");
    }
    if (!use_imu && !use_trajectory) {
      VIOSFM_LOG(WARNING) << "frame selection: no IMU and no trajectory, static frames are kept";
    } else {
      const StaticDetector forward(imu ? &*imu : nullptr, poses ? &*poses : nullptr, options);
      const StartTrim start = TrimStart(times, forward);
      if (!start.moving) {
        selection.status = FrameSelectionStatus::kNoMovingFrames;
        selection.message = "static: no moving frames (" + std::to_string(num_images) +
                            " images over " + FormatNsAsSeconds(times.back() - times.front(), 3) +
                            " s)";
        selection.decisions.assign(num_images, FrameDecision::kStatic);
        selection.motion_start_ns = selection.motion_end_ns = 0;
        return selection;
      }
      std::optional<ImuSignal> imu_mirrored;
      std::optional<PoseSignal> poses_mirrored;
      if (imu) imu_mirrored = imu->Mirrored();
      if (poses) poses_mirrored = poses->Mirrored();
      const StaticDetector backward(imu_mirrored ? &*imu_mirrored : nullptr,
                                    poses_mirrored ? &*poses_mirrored : nullptr, options);
      std::vector<timestamp_ns_t> mirrored_times(times.rbegin(), times.rend());
      for (timestamp_ns_t& t : mirrored_times) t = -t;
      const StartTrim end = TrimStart(mirrored_times, backward);
      first_kept = start.first_kept;
      selection.motion_start_ns = start.onset;
      if (end.moving) {
        last_kept = std::max(first_kept, num_images - 1 - end.first_kept);
        selection.motion_end_ns = -end.onset;
      }
    }
  }

  selection.decisions.assign(num_images, FrameDecision::kDownsampled);
  for (size_t k = 0; k < first_kept; ++k) selection.decisions[k] = FrameDecision::kStaticStart;
  for (size_t k = last_kept + 1; k < num_images; ++k) {
    selection.decisions[k] = FrameDecision::kStaticEnd;
  }
  std::vector<SequenceImage> moving(sequence.images.begin() + first_kept,
                                    sequence.images.begin() + last_kept + 1);
  const double rate_hz = EstimateFrameRateHz(moving);
  if (options.target_rate_hz > 0.0 && rate_hz > options.target_rate_hz * 1.01) {
    selection.kept = Downsample(times, first_kept, last_kept, options.target_rate_hz);
  } else {
    for (size_t k = first_kept; k <= last_kept; ++k) selection.kept.push_back(k);
  }
  for (const size_t k : selection.kept) selection.decisions[k] = FrameDecision::kKept;

  std::ostringstream message;
  message << "kept " << selection.kept.size() << " of " << num_images << " images (static start "
          << selection.Count(FrameDecision::kStaticStart) << ", static end "
          << selection.Count(FrameDecision::kStaticEnd) << ", downsampled "
          << selection.Count(FrameDecision::kDownsampled) << ")";
  selection.message = message.str();
  return selection;
}

GrowingFrameSelection::GrowingFrameSelection(const FrameSelectionOptions& options)
    : options_(options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("frame selection options: " + error);
  }
  double lag_s = 2.0 * options.static_window_s + options.imu_lowpass_s;
  if (options.target_rate_hz > 0.0) lag_s += 2.0 / options.target_rate_hz;
  lag_ns_ = SecondsToNs(lag_s);
}

std::vector<size_t> GrowingFrameSelection::Update(const Sequence& so_far, size_t* decided_until) {
  std::vector<size_t> selected;
  *decided_until = decided_;
  if (so_far.images.empty()) return selected;
  timestamp_ns_t latest_ns = so_far.images.back().timestamp_ns;
  if (so_far.has_imu()) latest_ns = std::min(latest_ns, so_far.imu.back().timestamp_ns);
  // The frames far enough behind the latest data.
  size_t until = decided_;
  while (until < so_far.images.size() && so_far.images[until].timestamp_ns + lag_ns_ < latest_ns) {
    ++until;
  }
  if (until == decided_) return selected;
  const FrameSelection selection = SelectFrames(so_far, options_);
  if (!selection.ok()) return selected;  // static so far: nothing to take yet
  // A trailing pause may be the static end: held until it is not.
  if (selection.motion_end_ns < so_far.images.back().timestamp_ns) {
    while (until > decided_ && so_far.images[until - 1].timestamp_ns > selection.motion_end_ns) {
      --until;
    }
  }
  for (const size_t k : selection.kept) {
    if (k >= decided_ && k < until) selected.push_back(k);
  }
  decided_ = until;
  taken_.insert(taken_.end(), selected.begin(), selected.end());
  *decided_until = decided_;
  return selected;
}

std::vector<size_t> GrowingFrameSelection::Finish(const Sequence& whole,
                                                  FrameSelection* selection) {
  *selection = SelectFrames(whole, options_);
  std::vector<size_t> selected;
  if (!selection->ok()) {
    selection->kept = taken_;
    return selected;
  }
  size_t not_taken = 0;
  size_t taken_extra = 0;
  for (const size_t k : selection->kept) {
    if (k >= decided_) {
      selected.push_back(k);
    } else if (!std::binary_search(taken_.begin(), taken_.end(), k)) {
      ++not_taken;  // kept by the whole recording, not taken as it grew
    }
  }
  for (const size_t k : taken_) {
    if (!std::binary_search(selection->kept.begin(), selection->kept.end(), k)) {
      ++taken_extra;  // taken as it grew, not kept by the whole
      selection->decisions[k] = FrameDecision::kKept;
    }
  }
  std::vector<size_t> kept = taken_;
  kept.insert(kept.end(), selected.begin(), selected.end());
  if (not_taken + taken_extra > 0) {
    VIOSFM_LOG(WARNING) << "frame selection: as the recording grew, " << not_taken
                        << " frame(s) that the whole recording's selection keeps were left out "
                           "(not reconstructed) and "
                        << taken_extra
                        << " it leaves out were taken (reconstructed): decided before the "
                           "data after them came";
  }
  selection->kept = std::move(kept);
  taken_.insert(taken_.end(), selected.begin(), selected.end());
  decided_ = whole.images.size();
  return selected;
}

}  // namespace viosfm

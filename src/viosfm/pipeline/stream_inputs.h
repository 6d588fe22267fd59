// What a stream's threads share of the recording: its frames in time order
// and its IMU, both growing while a recording is followed.
#pragma once

#include <Eigen/Core>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "viosfm/io/dataset.h"
#include "viosfm/scene/rolling_shutter.h"

namespace viosfm {

// The frames the stream takes, in time order: all known up front (a
// recorded dataset) or added as a followed recording's frame selection
// takes them.
class FrameQueue {
 public:
  void Add(const SequenceImage& image) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      images_.push_back(image);
    }
    changed_.notify_all();
  }
  void Close() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    changed_.notify_all();
  }
  void Fail(const std::string& message) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      failure_ = message;
    }
    changed_.notify_all();
  }
  // Blocks until frame k is known (true) or every frame is (false).
  // Throws std::runtime_error if the source failed.
  bool Get(size_t k, SequenceImage* image) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return k < images_.size() || closed_ || !failure_.empty(); });
    if (!failure_.empty()) throw std::runtime_error(failure_);
    if (k >= images_.size()) return false;
    *image = images_[k];
    return true;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<SequenceImage> images_;
  bool closed_ = false;
  std::string failure_;
};

// The IMU as far as it has come (a followed recording's grows).
class SharedImu {
 public:
  void Add(const std::vector<ImuSample>& samples) {
    const std::lock_guard<std::mutex> lock(mutex_);
    samples_.insert(samples_.end(), samples.begin(), samples.end());
  }
  bool empty() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return samples_.empty();
  }
  // scene/rolling_shutter.h CamAngularRate on the samples so far.
  Eigen::Vector3d CamAngularRateAt(const SensorRig& rig, timestamp_ns_t stamp_ns) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return CamAngularRate(rig, samples_, stamp_ns);
  }
  std::vector<ImuSample> All() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return samples_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<ImuSample> samples_;
};

}  // namespace viosfm

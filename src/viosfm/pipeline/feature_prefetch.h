// Feature extraction beside viosfm's own VIO.
//
// The VIO decodes every frame and uses one core; the features stage, after
// it, decodes nothing (the frames wait in the frame cache) but extracts SIFT
// from every selected frame. When the frames the features stage will take
// are known before the VIO (the frame selection does not need the VIO's
// trajectory), a FeaturePrefetch thread follows the VIO through them on the
// second core: it takes each frame from the frame cache as soon as the VIO
// has read it, extracts its SIFT features with the run's options and keeps
// them, with their keypoints' grey values, in memory up to a byte budget.
// The thread runs at a lower priority (nice 10) than the VIO, which the run
// waits for: it takes the core the VIO leaves idle, and when both want the
// same core, the VIO gets it.
// The features stage then writes those instead of extracting them
// (ExtractFeatures' FeatureImageAccess::take_extracted) and extracts the
// rest. Nothing reaches the run folder before the features stage (the
// run's fingerprint, which includes the VIO poses, is checked first): the
// database is the same as without it, byte for byte.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/frame_cache.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

class FeaturePrefetch {
 public:
  // Starts the thread: it follows `paths` in order (the frames the
  // features stage will take, in the order the VIO reads them), taking each
  // from `frames` once read (FrameCache::TakeAfterRead), until it holds
  // `max_bytes` of features, a frame is not the camera's size or cannot be
  // read (left to the features stage, which reports it), or Finish.
  // With `wait_when_full` (a consumer that takes every frame in order, the
  // streamed run) the thread waits at `max_bytes` until the consumer has
  // taken some, instead of stopping there.
  // With `more_paths`, paths come after these too (AddPath), until
  // ClosePaths: the frames of a recording that grows.
  FeaturePrefetch(std::vector<std::filesystem::path> paths, const SiftOptions& options,
                  const Camera& camera, FrameCache* frames, size_t max_bytes,
                  bool wait_when_full = false, bool more_paths = false);
  ~FeaturePrefetch();  // Finish
  FeaturePrefetch(const FeaturePrefetch&) = delete;
  FeaturePrefetch& operator=(const FeaturePrefetch&) = delete;

  // The SIFT options of the frames it has not begun (a followed recording's
  // feature count is settled by its texture probe after the thread starts).
  void SetSiftOptions(const SiftOptions& options);
  // One more path to follow, after those given (with more_paths).
  void AddPath(const std::filesystem::path& path);
  // No more paths come (with more_paths).
  void ClosePaths();

  // The reader is done: the thread finishes the frame it is on and stops
  // (the features stage, on every core, extracts the rest); joins it.
  // Idempotent.
  void Finish();

  // The features and keypoint grey values extracted for `path`, moved out;
  // false if there are none. Thread-safe.
  bool Take(const std::filesystem::path& path, ImageFeatures* features,
            std::vector<uint8_t>* grey_values);

  // Take, once the thread has extracted `path` or stopped before it (then
  // false: the caller extracts it). Thread-safe.
  bool WaitAndTake(const std::filesystem::path& path, ImageFeatures* features,
                   std::vector<uint8_t>* grey_values);

  size_t num_extracted() const { return num_extracted_; }  // after Finish: final
  size_t peak_bytes() const { return peak_bytes_; }        // most held at once

 private:
  struct Extracted {
    ImageFeatures features;
    std::vector<uint8_t> grey_values;
    size_t bytes = 0;
  };
  void Follow();
  void FollowPaths();

  std::vector<std::filesystem::path> paths_;  // under mutex_ with more_paths
  bool paths_closed_ = true;
  SiftOptions options_;  // under mutex_
  const Camera camera_;
  FrameCache* const frames_;
  const size_t max_bytes_;
  const bool wait_when_full_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool done_ = false;  // the thread has stopped
  std::map<std::filesystem::path, Extracted> extracted_;
  size_t held_bytes_ = 0;
  std::atomic<size_t> num_extracted_{0};
  std::atomic<size_t> peak_bytes_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace viosfm

#include "viosfm/pipeline/feature_prefetch.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <exception>
#include <utility>

#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

constexpr int kNiceness = 10;

}  // namespace

FeaturePrefetch::FeaturePrefetch(std::vector<std::filesystem::path> paths,
                                 const SiftOptions& options, const Camera& camera,
                                 FrameCache* frames, size_t max_bytes, bool wait_when_full,
                                 bool more_paths)
    : paths_(std::move(paths)),
      paths_closed_(!more_paths),
      options_(options),
      camera_(camera),
      frames_(frames),
      max_bytes_(max_bytes),
      wait_when_full_(wait_when_full) {
  VIOSFM_CHECK(frames_ != nullptr);
  thread_ = std::thread([this] { Follow(); });
}

FeaturePrefetch::~FeaturePrefetch() {
  Finish();
}

void FeaturePrefetch::Finish() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  frames_->StopWaiting();
  if (thread_.joinable()) thread_.join();
}

void FeaturePrefetch::Follow() {
  // Below the VIO's priority: the VIO is what the run waits for, this
  // thread only fills the core it leaves idle (Linux: per thread).
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kNiceness);
  FollowPaths();
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  changed_.notify_all();
}

void FeaturePrefetch::SetSiftOptions(const SiftOptions& options) {
  const std::lock_guard<std::mutex> lock(mutex_);
  options_ = options;
}

void FeaturePrefetch::AddPath(const std::filesystem::path& path) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    VIOSFM_CHECK(!paths_closed_) << "a path added after ClosePaths";
    paths_.push_back(path);
  }
  changed_.notify_all();
}

void FeaturePrefetch::ClosePaths() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    paths_closed_ = true;
  }
  changed_.notify_all();
}

void FeaturePrefetch::FollowPaths() {
  for (size_t index = 0;; ++index) {
    std::filesystem::path path;
    SiftOptions sift;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || index < paths_.size() || paths_closed_; });
      if (stop_ || index >= paths_.size()) return;
      path = paths_[index];
      sift = options_;
    }
    Extracted extracted;
    try {
      const std::shared_ptr<const GreyImage> pixels = frames_->TakeAfterRead(path);
      if (pixels == nullptr) return;  // the VIO did not read it
      if (static_cast<uint64_t>(pixels->width) != camera_.width ||
          static_cast<uint64_t>(pixels->height) != camera_.height) {
        return;  // the features stage reads it again and reports the size
      }
      extracted.features = ExtractSift(*pixels, sift);
      extracted.grey_values = SampleKeypointGreyValues(*pixels, extracted.features.keypoints);
    } catch (const std::exception& error) {
      // The features stage reads the image again and reports what is wrong.
      VIOSFM_LOG(INFO) << "run: features beside the VIO stop at " << path.string() << ": "
                       << error.what();
      return;
    }
    extracted.bytes = extracted.features.keypoints.size() * sizeof(FeatureKeypoint) +
                      static_cast<size_t>(extracted.features.descriptors.size()) +
                      extracted.grey_values.size();
    std::unique_lock<std::mutex> lock(mutex_);
    held_bytes_ += extracted.bytes;
    peak_bytes_ = std::max(peak_bytes_.load(), held_bytes_);
    extracted_.emplace(path, std::move(extracted));
    ++num_extracted_;
    changed_.notify_all();
    if (held_bytes_ >= max_bytes_) {
      if (!wait_when_full_) return;  // the rest stays in the frame cache
      changed_.wait(lock, [&] { return held_bytes_ < max_bytes_ || stop_; });
    }
  }
}

bool FeaturePrefetch::WaitAndTake(const std::filesystem::path& path, ImageFeatures* features,
                                  std::vector<uint8_t>* grey_values) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return done_ || extracted_.count(path) > 0; });
  }
  return Take(path, features, grey_values);
}

bool FeaturePrefetch::Take(const std::filesystem::path& path, ImageFeatures* features,
                           std::vector<uint8_t>* grey_values) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = extracted_.find(path);
  if (it == extracted_.end()) return false;
  *features = std::move(it->second.features);
  *grey_values = std::move(it->second.grey_values);
  held_bytes_ -= it->second.bytes;
  extracted_.erase(it);
  changed_.notify_all();
  return true;
}

}  // namespace viosfm

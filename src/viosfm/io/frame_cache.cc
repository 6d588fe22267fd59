#include "viosfm/io/frame_cache.h"

#include <algorithm>

#include "viosfm/io/image_io.h"

namespace viosfm {

namespace fs = std::filesystem;

std::shared_ptr<const GreyImage> FrameCache::Read(const fs::path& path, bool keep) {
  return Fetch(path, keep, /*mark_read=*/true);
}

std::shared_ptr<const GreyImage> FrameCache::Preload(const fs::path& path) {
  return Fetch(path, /*keep=*/true, /*mark_read=*/false);
}

std::shared_ptr<const GreyImage> FrameCache::Fetch(const fs::path& path, bool keep,
                                                   bool mark_read) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = held_.find(path); it != held_.end()) {
      ++counts_.reuses;
      if (mark_read && read_.insert(path).second) read_done_.notify_all();
      return it->second;
    }
  }
  auto image = std::make_shared<const GreyImage>(ReadGreyImage(path));
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.decodes;
  if (mark_read && read_.insert(path).second) read_done_.notify_all();
  if (keep && (!filtered_ || wanted_.count(path) > 0) && released_.count(path) == 0) {
    const size_t bytes = image->pixels.size();
    if (held_bytes_ + bytes <= max_bytes_) {
      if (held_.emplace(path, image).second) held_bytes_ += bytes;
      counts_.peak_bytes = std::max(counts_.peak_bytes, held_bytes_);
    } else {
      ++counts_.not_kept;
    }
  }
  return image;
}

std::shared_ptr<const GreyImage> FrameCache::Take(const fs::path& path) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = held_.find(path); it != held_.end()) {
      std::shared_ptr<const GreyImage> image = std::move(it->second);
      held_bytes_ -= image->pixels.size();
      held_.erase(it);
      ++counts_.reuses;
      return image;
    }
  }
  auto image = std::make_shared<const GreyImage>(ReadGreyImage(path));
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.decodes;
  return image;
}

std::shared_ptr<const GreyImage> FrameCache::TakeAfterRead(const fs::path& path) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    read_done_.wait(lock, [&] { return stop_waiting_ || read_.count(path) > 0; });
    if (read_.count(path) == 0) return nullptr;
  }
  return Take(path);
}

void FrameCache::StopWaiting() {
  std::lock_guard<std::mutex> lock(mutex_);
  stop_waiting_ = true;
  read_done_.notify_all();
}

void FrameCache::RetainOnly(const std::vector<fs::path>& paths) {
  std::set<fs::path> wanted(paths.begin(), paths.end());
  std::lock_guard<std::mutex> lock(mutex_);
  filtered_ = true;
  wanted_ = std::move(wanted);
  for (auto it = held_.begin(); it != held_.end();) {
    if (wanted_.count(it->first) > 0) {
      ++it;
    } else {
      held_bytes_ -= it->second->pixels.size();
      it = held_.erase(it);
    }
  }
}

void FrameCache::Release(const fs::path& path) {
  std::lock_guard<std::mutex> lock(mutex_);
  released_.insert(path);
  const auto it = held_.find(path);
  if (it == held_.end()) return;
  held_bytes_ -= it->second->pixels.size();
  held_.erase(it);
}

FrameCache::Counts FrameCache::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

}  // namespace viosfm

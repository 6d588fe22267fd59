// The decoded images of one run, so that each image file is decoded once.
//
// The VIO decodes every frame of the sequence; the frames a later stage
// needs (the selected frames, for feature extraction) are kept here and
// taken from here instead of being decoded again. Colours need no image:
// feature extraction samples each keypoint's grey value as it goes.
//
// Bounded: a frame past max_bytes of held pixels is not kept (it is decoded
// again when taken, and counted so). Thread-safe.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

#include "viosfm/sensor/grey_image.h"

namespace viosfm {

class FrameCache {
 public:
  struct Counts {
    size_t decodes = 0;     // image files decoded
    size_t reuses = 0;      // images taken from the cache instead of decoded
    size_t not_kept = 0;    // frames not kept for lack of room
    size_t peak_bytes = 0;  // most pixel bytes held at once
  };

  explicit FrameCache(size_t max_bytes) : max_bytes_(max_bytes) {}

  // The image at `path` as 8-bit grey (io/image_io.h ReadGreyImage): the
  // held copy if there is one, else decoded now; with `keep`, held for a
  // later Take if there is room. Throws InputError as ReadGreyImage does.
  std::shared_ptr<const GreyImage> Read(const std::filesystem::path& path, bool keep);
  // Read with `keep`, by someone other than the reader that TakeAfterRead
  // follows: the image is held for later, but a TakeAfterRead of it still
  // waits for the reader's own Read (which then finds it held).
  std::shared_ptr<const GreyImage> Preload(const std::filesystem::path& path);
  // The image for the last time: the held copy, released, or decoded now.
  std::shared_ptr<const GreyImage> Take(const std::filesystem::path& path);
  // Take once `path` has been Read, decoded or found held (by another thread: a stage that runs
  // beside the reader takes each frame right after it); blocks until then.
  // Null if StopWaiting came first.
  std::shared_ptr<const GreyImage> TakeAfterRead(const std::filesystem::path& path);
  // Wakes every TakeAfterRead waiting for a path not read yet, and makes
  // later ones return null at once for such paths (the reader is done).
  void StopWaiting();
  // Releases every held image whose path is not in `paths`, and from now on
  // keeps only images in `paths` (the frames a later stage will take).
  void RetainOnly(const std::vector<std::filesystem::path>& paths);
  // Releases the held copy of `path`, if any, and keeps none of it later (a
  // frame no later stage takes: a recording's frames are decided one by one
  // as it grows, some before the reader has read them).
  void Release(const std::filesystem::path& path);

  Counts counts() const;
  size_t max_bytes() const { return max_bytes_; }

 private:
  std::shared_ptr<const GreyImage> Fetch(const std::filesystem::path& path, bool keep,
                                         bool mark_read);

  const size_t max_bytes_;
  mutable std::mutex mutex_;
  std::map<std::filesystem::path, std::shared_ptr<const GreyImage>> held_;
  bool filtered_ = false;                     // RetainOnly was called
  std::set<std::filesystem::path> wanted_;    // then: the only paths kept
  std::set<std::filesystem::path> released_;  // Release: never kept
  size_t held_bytes_ = 0;
  Counts counts_;
  std::set<std::filesystem::path> read_;  // paths Read so far
  bool stop_waiting_ = false;
  std::condition_variable read_done_;
};

}  // namespace viosfm

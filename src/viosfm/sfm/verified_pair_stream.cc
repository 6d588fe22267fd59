#include "viosfm/sfm/verified_pair_stream.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm {

VerifiedPairStream::VerifiedPairStream(std::vector<image_t> image_ids,
                                       std::vector<timestamp_ns_t> timestamps_ns)
    : frames_up_front_(true),
      timestamps_ns_(std::move(timestamps_ns)),
      pairs_by_later_frame_(image_ids.size()) {
  VIOSFM_CHECK_EQ(image_ids.size(), timestamps_ns_.size());
  for (size_t i = 0; i < image_ids.size(); ++i) {
    VIOSFM_CHECK(index_of_image_.emplace(image_ids[i], i).second)
        << "image " << image_ids[i] << " listed twice";
    VIOSFM_CHECK(i == 0 || timestamps_ns_[i] > timestamps_ns_[i - 1])
        << "frames not in strictly increasing time order at " << i;
  }
}

VerifiedPairStream::VerifiedPairStream() : frames_up_front_(false) {}

size_t VerifiedPairStream::num_frames() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return timestamps_ns_.size();
}

void VerifiedPairStream::AddFrame(MapperImage frame) {
  VIOSFM_CHECK(!frames_up_front_) << "a frame added to a stream whose frames were given up front";
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    VIOSFM_CHECK(!closed_) << "a frame added to a closed stream";
    if (!timestamps_ns_.empty() && frame.timestamp_ns <= timestamps_ns_.back()) {
      throw InputError("streamed frame " + std::to_string(frame.image_id) + " at " +
                       FormatNsAsSeconds(frame.timestamp_ns) +
                       " s does not follow the last frame, at " +
                       FormatNsAsSeconds(timestamps_ns_.back()) + " s");
    }
    if (!index_of_image_.emplace(frame.image_id, timestamps_ns_.size()).second) {
      throw InputError("streamed frame " + std::to_string(frame.image_id) + " added twice");
    }
    timestamps_ns_.push_back(frame.timestamp_ns);
    pairs_by_later_frame_.emplace_back();
    added_frames_.push_back(std::move(frame));
  }
  changed_.notify_all();
}

void VerifiedPairStream::Add(std::vector<ImagePairMatches> pairs, timestamp_ns_t pending_from_ns) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::vector<size_t> later_frames;
    later_frames.reserve(pairs.size());
    for (const ImagePairMatches& pair : pairs) {
      const auto it1 = index_of_image_.find(pair.image_id1);
      const auto it2 = index_of_image_.find(pair.image_id2);
      if (it1 == index_of_image_.end() || it2 == index_of_image_.end()) {
        throw InputError(
            "verified pair (images " + std::to_string(pair.image_id1) + ", " +
            std::to_string(pair.image_id2) + ") refers to unknown image id " +
            std::to_string(it1 == index_of_image_.end() ? pair.image_id1 : pair.image_id2));
      }
      later_frames.push_back(std::max(it1->second, it2->second));
    }
    for (size_t p = 0; p < pairs.size(); ++p) {
      // A pair behind the frontier the producer promised, or of frames the
      // consumer has taken already, would be lost: the producer's bug.
      VIOSFM_CHECK(later_frames[p] >= taken_until_ &&
                   timestamps_ns_[later_frames[p]] >= frontier_ns_)
          << "verified pair (images " << pairs[p].image_id1 << ", " << pairs[p].image_id2
          << ") added behind the frontier";
      pairs_by_later_frame_[later_frames[p]].push_back(std::move(pairs[p]));
    }
    frontier_ns_ = std::max(frontier_ns_, pending_from_ns);
  }
  changed_.notify_all();
}

void VerifiedPairStream::Close() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    frontier_ns_ = kClosed;
  }
  changed_.notify_all();
}

void VerifiedPairStream::Fail(const std::string& message) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    failure_ = message.empty() ? "the verification failed" : message;
  }
  changed_.notify_all();
}

bool VerifiedPairStream::Known(size_t end) const {
  return frames_up_front_ || closed_ || timestamps_ns_.size() > end;
}

size_t VerifiedPairStream::Available(size_t end) const {
  return std::min(end, timestamps_ns_.size());
}

VerifiedPairStream::Taken VerifiedPairStream::Take(size_t end) {
  std::unique_lock<std::mutex> lock(mutex_);
  VIOSFM_CHECK_GE(end, taken_until_) << "frames taken out of order";
  // The frames up to `end` known, and the pairs whose later frame is the
  // last of them all in once the frontier has passed its stamp.
  const auto complete = [&] {
    if (!failure_.empty()) return true;
    if (!Known(end)) return false;
    const size_t available = Available(end);
    return available == 0 || frontier_ns_ > timestamps_ns_[available - 1];
  };
  changed_.wait(lock, complete);
  if (!failure_.empty()) throw std::runtime_error(failure_);
  Taken taken;
  taken.end = std::max(taken_until_, Available(end));
  taken.last = (frames_up_front_ || closed_) && taken.end == timestamps_ns_.size();
  for (size_t i = taken_until_; i < taken.end; ++i) {
    for (ImagePairMatches& pair : pairs_by_later_frame_[i]) taken.pairs.push_back(std::move(pair));
    pairs_by_later_frame_[i].clear();
    pairs_by_later_frame_[i].shrink_to_fit();
  }
  if (!frames_up_front_) {
    for (size_t i = frames_taken_; i < taken.end; ++i) {
      taken.frames.push_back(std::move(added_frames_[i - frames_taken_]));
    }
    added_frames_.erase(added_frames_.begin(),
                        added_frames_.begin() + static_cast<ptrdiff_t>(taken.end - frames_taken_));
    frames_taken_ = taken.end;
  }
  taken_until_ = taken.end;
  return taken;
}

}  // namespace viosfm

#include "viosfm/sfm/verified_pair_stream.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm {

VerifiedPairStream::VerifiedPairStream(std::vector<image_t> image_ids,
                                       std::vector<timestamp_ns_t> timestamps_ns)
    : timestamps_ns_(std::move(timestamps_ns)), pairs_by_first_frame_(image_ids.size()) {
  VIOSFM_CHECK_EQ(image_ids.size(), timestamps_ns_.size());
  for (size_t i = 0; i < image_ids.size(); ++i) {
    VIOSFM_CHECK(index_of_image_.emplace(image_ids[i], i).second)
        << "image " << image_ids[i] << " listed twice";
    VIOSFM_CHECK(i == 0 || timestamps_ns_[i] > timestamps_ns_[i - 1])
        << "frames not in strictly increasing time order at " << i;
  }
}

void VerifiedPairStream::Add(std::vector<ImagePairMatches> pairs, timestamp_ns_t pending_from_ns) {
  std::vector<size_t> first_frames;
  first_frames.reserve(pairs.size());
  for (const ImagePairMatches& pair : pairs) {
    const auto it1 = index_of_image_.find(pair.image_id1);
    const auto it2 = index_of_image_.find(pair.image_id2);
    if (it1 == index_of_image_.end() || it2 == index_of_image_.end()) {
      throw InputError(
          "verified pair (images " + std::to_string(pair.image_id1) + ", " +
          std::to_string(pair.image_id2) + ") refers to unknown image id " +
          std::to_string(it1 == index_of_image_.end() ? pair.image_id1 : pair.image_id2));
    }
    first_frames.push_back(std::min(it1->second, it2->second));
  }
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (size_t p = 0; p < pairs.size(); ++p) {
      // A pair behind the frontier the producer promised, or of frames the
      // consumer has taken already, would be lost: the producer's bug.
      VIOSFM_CHECK(first_frames[p] >= taken_until_ &&
                   timestamps_ns_[first_frames[p]] >= frontier_ns_)
          << "verified pair (images " << pairs[p].image_id1 << ", " << pairs[p].image_id2
          << ") added behind the frontier";
      pairs_by_first_frame_[first_frames[p]].push_back(std::move(pairs[p]));
    }
    frontier_ns_ = std::max(frontier_ns_, pending_from_ns);
  }
  frontier_moved_.notify_all();
}

void VerifiedPairStream::Fail(const std::string& message) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    failure_ = message.empty() ? "the verification failed" : message;
  }
  frontier_moved_.notify_all();
}

std::vector<ImagePairMatches> VerifiedPairStream::TakeUntil(size_t end) {
  end = std::min(end, timestamps_ns_.size());
  std::unique_lock<std::mutex> lock(mutex_);
  VIOSFM_CHECK_GE(end, taken_until_) << "frames taken out of order";
  // The pairs whose earlier frame is end - 1 are all in once the frontier
  // has passed that frame's stamp.
  const auto complete = [&] {
    return !failure_.empty() || end == 0 || frontier_ns_ > timestamps_ns_[end - 1];
  };
  frontier_moved_.wait(lock, complete);
  if (!failure_.empty()) throw std::runtime_error(failure_);
  std::vector<ImagePairMatches> taken;
  for (size_t i = taken_until_; i < end; ++i) {
    for (ImagePairMatches& pair : pairs_by_first_frame_[i]) taken.push_back(std::move(pair));
    pairs_by_first_frame_[i].clear();
    pairs_by_first_frame_[i].shrink_to_fit();
  }
  taken_until_ = end;
  return taken;
}

}  // namespace viosfm

// Verified pairs handed from the verification to a mapper running beside it
// (pipeline/pipeline.h, `pipeline.stream_mapper`).
//
// The verification decides its pairs in an order of its own and reports,
// after each batch, the accepted ones and a frontier: every pair still to
// come has both its frames at or after the frontier's stamp. The mapper
// registers its frames in batches of time order; before mapping the frames
// [0, end) it takes every pair whose earlier frame lies in [0, end), once
// the frontier has passed frame end - 1. That set does not depend on how
// far the verification has run ahead, so a streamed run maps the same
// pairs batch by batch whatever the two threads' timing: its result is
// reproducible. The pairs a batch sees are complete among its frames and
// those before (every consecutive pair, every pair crossing a cut before
// `end`), so the tracks and the relative-pose priors of the frames mapped so
// far are those of the whole set of pairs; later pairs can only extend them.
#pragma once

#include <condition_variable>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

class VerifiedPairStream {
 public:
  // The frames' ids and stamps, in strictly increasing time order (the
  // mapper's input images).
  VerifiedPairStream(std::vector<image_t> image_ids, std::vector<timestamp_ns_t> timestamps_ns);

  // Producer. Adds accepted pairs (ids of the frames given; InputError
  // otherwise) and moves the frontier to `pending_from_ns`: every pair added
  // later has both frames at or after that stamp. The frontier never moves
  // back.
  void Add(std::vector<ImagePairMatches> pairs, timestamp_ns_t pending_from_ns);
  // Every pair has been added.
  void Close() { Add({}, kClosed); }
  // The producer failed: the consumer's TakeUntil throws with `message`.
  void Fail(const std::string& message);

  // Consumer. Blocks until every pair whose earlier frame has an index below
  // `end` has been added, then returns those not returned before (earlier
  // frame in [the previous call's end, end)), by earlier frame, each frame's
  // in the order they were added. `end` must not decrease (CHECK). Throws
  // std::runtime_error if the producer failed.
  std::vector<ImagePairMatches> TakeUntil(size_t end);

  size_t num_frames() const { return timestamps_ns_.size(); }

 private:
  static constexpr timestamp_ns_t kClosed = std::numeric_limits<timestamp_ns_t>::max();

  std::unordered_map<image_t, size_t> index_of_image_;
  std::vector<timestamp_ns_t> timestamps_ns_;
  std::mutex mutex_;
  std::condition_variable frontier_moved_;
  // The pairs added and not taken, by the index of their earlier frame.
  std::vector<std::vector<ImagePairMatches>> pairs_by_first_frame_;
  timestamp_ns_t frontier_ns_ = std::numeric_limits<timestamp_ns_t>::min();
  size_t taken_until_ = 0;
  std::string failure_;
};

}  // namespace viosfm

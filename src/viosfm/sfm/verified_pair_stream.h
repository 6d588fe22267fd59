// Verified pairs, and the frames they join, handed from the verification to
// a mapper running beside it (pipeline/pipeline.h `pipeline.stream_mapper`,
// and the streamed run, pipeline/stream_pipeline.h).
//
// The frames are either known up front (their ids and stamps: the mapper's
// input holds them) or added one by one as the run reaches them (AddFrame:
// the mapper takes them from here with the pairs). The verification decides
// its pairs in an order of its own and reports, after each handful, the
// accepted ones and a frontier: every pair still to come has its later frame
// at or after the frontier's stamp. The mapper registers its frames in
// batches of time order; before mapping the frames [0, end) it takes every
// pair whose later frame lies in [0, end), once the frontier has passed
// frame end - 1. That set does not depend on how far the verification has
// run ahead, so a streamed run maps the same pairs batch by batch whatever
// the threads' timing: its result is reproducible. The pairs a batch sees
// are every pair among its frames and those before it, so the tracks and
// the consecutive relative-pose priors of the frames mapped so far are
// those of the whole set of pairs; later pairs (a later frame's, a loop
// closed by retrieval) can only extend them.
#pragma once

#include <condition_variable>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/sfm/mapper_input.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

class VerifiedPairStream {
 public:
  // The frames known up front: ids and stamps, in strictly increasing time
  // order (the mapper's input images; CHECKed).
  VerifiedPairStream(std::vector<image_t> image_ids, std::vector<timestamp_ns_t> timestamps_ns);
  // The frames come with AddFrame.
  VerifiedPairStream();

  // Producer. A frame after every frame added before it (a stream made
  // with its frames up front takes none); InputError for a frame not later
  // than the last or an id added before. A frame's pairs are added after it.
  void AddFrame(MapperImage frame);
  // Adds accepted pairs (of frames known; InputError otherwise) and moves
  // the frontier to `pending_from_ns`: every pair added later has its later
  // frame at or after that stamp. The frontier never moves back.
  void Add(std::vector<ImagePairMatches> pairs, timestamp_ns_t pending_from_ns);
  // Every frame and pair has been added.
  void Close();
  // The producer failed: the consumer's Take throws with `message`.
  void Fail(const std::string& message);

  struct Taken {
    // The frames [the previous call's end, end) as added with AddFrame
    // (none for frames known up front).
    std::vector<MapperImage> frames;
    // Every pair whose later frame lies in [the previous call's end, end),
    // by later frame, each frame's in the order they were added.
    std::vector<ImagePairMatches> pairs;
    // The frames taken so far: the `end` asked for, or fewer when the
    // stream closed with fewer frames.
    size_t end = 0;
    // No frame comes after them.
    bool last = false;
  };
  // Consumer. Blocks until the frames [0, end) are known (or the stream has
  // closed with fewer), every pair whose later frame is one of them has been
  // added, and it is known whether more frames follow; then returns what
  // was not returned before. `end` must not decrease (CHECK). Throws
  // std::runtime_error if the producer failed.
  Taken Take(size_t end);

  // Frames known up front (the first constructor).
  bool frames_up_front() const { return frames_up_front_; }
  // Up front: their number; else the frames added so far.
  size_t num_frames() const;

 private:
  static constexpr timestamp_ns_t kClosed = std::numeric_limits<timestamp_ns_t>::max();

  // Both under mutex_.
  bool Known(size_t end) const;
  size_t Available(size_t end) const;

  const bool frames_up_front_;
  mutable std::mutex mutex_;
  std::unordered_map<image_t, size_t> index_of_image_;
  std::vector<timestamp_ns_t> timestamps_ns_;
  // The frames added and not taken (AddFrame), from index frames_taken_.
  std::vector<MapperImage> added_frames_;
  size_t frames_taken_ = 0;
  std::condition_variable changed_;
  // The pairs added and not taken, by the index of their later frame.
  std::vector<std::vector<ImagePairMatches>> pairs_by_later_frame_;
  timestamp_ns_t frontier_ns_ = std::numeric_limits<timestamp_ns_t>::min();
  bool closed_ = false;
  size_t taken_until_ = 0;
  std::string failure_;
};

}  // namespace viosfm

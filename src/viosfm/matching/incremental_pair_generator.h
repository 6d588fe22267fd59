// Which image pairs to match, decided frame by frame: the pairs of each
// frame with the frames before it, as soon as they are fixed. In the shape of
// COLMAP's pair generators (Next(), HasFinished()), for frames that arrive
// in time order: a recording being made, or a recorded one fed in order (a
// batch is a stream that happens to be complete).
//
// Frame d's pairs are those whose later frame is d, in the modes of
// pair_generator.h:
//  - temporal+retrieval: every earlier frame i with i among d's N1 temporal
//    neighbours or d among i's, and every earlier frame i with i among d's
//    N2 retrieval neighbours or d among i's (those beyond each frame's
//    temporal ones). So over all frames the pairs are TemporalRetrievalPairs'.
//    d's temporal neighbours are fixed once N1 frames after it are known (or
//    every frame is), its retrieval neighbours once SetRetrieved gave them
//    for it and every earlier frame;
//  - sequential: the N1 frames before d;
//  - exhaustive: every frame before d.
#pragma once

#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "viosfm/matching/pair_generator.h"
#include "viosfm/util/types.h"

namespace viosfm {

// A pair to verify: an earlier frame and how the pair was proposed
// ("temporal", "retrieval", "sequential", "exhaustive").
struct ProposedPair {
  size_t earlier_frame = 0;
  const char* source = "";
};

class IncrementalPairGenerator {
 public:
  // `options.mode` must not be kPairList (InputError).
  explicit IncrementalPairGenerator(const PairGeneratorOptions& options);

  // The next frame (after every frame added before it); returns its index.
  size_t AddFrame(const PairGeneratorImage& image);
  // No frame comes after those added.
  void FinishFrames() { frames_finished_ = true; }
  // Frame k's visually similar frames, most similar first (ids; any in
  // time, unknown ones skipped): retrieval among the earlier frames of a
  // stream, or among every frame of a recording known up front. Needed
  // before frame k or a later one is decided, when the mode has retrieval
  // neighbours (SetRetrievalUsed).
  void SetRetrieved(size_t k, std::vector<image_t> ranked);
  // Whether retrieval neighbours are proposed (temporal+retrieval with N2 > 0
  // and a retrieval the caller runs). Default true.
  void SetRetrievalUsed(bool used) { retrieval_used_ = used; }

  // The next frame's pairs with the frames before it, once they are fixed:
  // false (and nothing taken) while they are not.
  bool Next(size_t* frame, std::vector<ProposedPair>* pairs);
  // Every frame's pairs have been taken.
  bool HasFinished() const;
  // The frame Next decides next.
  size_t next_frame() const { return next_; }
  size_t num_frames() const { return images_.size(); }
  const PairGeneratorImage& image(size_t k) const { return images_[k]; }
  // Frame k's temporal neighbours, once Next has passed it (else empty).
  const std::vector<size_t>& TemporalNeighborsOf(size_t k) const { return temporal_[k]; }

 private:
  bool Decidable(size_t d) const;
  // The first N2 of frame k's retrieved frames beyond its temporal
  // neighbours (frame indices).
  const std::vector<size_t>& RetrievalNeighborsOf(size_t k);

  PairGeneratorOptions options_;
  std::vector<PairGeneratorImage> images_;
  std::unordered_map<image_t, size_t> frame_of_image_;
  std::vector<std::optional<std::vector<image_t>>> retrieved_;
  std::vector<std::vector<size_t>> temporal_;
  std::vector<std::optional<std::vector<size_t>>> retrieval_neighbors_;
  std::vector<std::vector<size_t>> later_retrieval_partners_;  // frames that retrieved k
  size_t next_ = 0;
  bool frames_finished_ = false;
  bool retrieval_used_ = true;
};

}  // namespace viosfm

// Retrieval for frames that arrive one at a time (the streamed run,
// pipeline/stream_pipeline.h): each frame is compared with the frames before
// it only, so that its retrieval pairs are known as soon as it is, and a
// later frame finds the earlier ones it revisits (a loop closes from its
// later end).
//
// The vocabulary tree is the file options.vocabulary_path's, or trained on
// the descriptors of the first `num_training_frames` frames (the batch run
// trains on the whole sequence, which a stream does not have). The inverted
// file weighs words by TF-IDF as inverted_index.h does, with the inverse
// document frequencies of those training frames, kept from then on: an
// image's weighted vector then never changes, so the index only grows, and
// a frame's scores against the frames before it do not depend on the frames
// after it. Until the vocabulary exists the frames wait; once it does, each
// of them is compared with the waiting frames before it.
//
// Excluded from a frame's candidates: the `num_temporal_neighbors` frames
// just before it (the temporal pairs join those anyway).
#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "viosfm/retrieval/image_retrieval.h"
#include "viosfm/retrieval/vocabulary_tree.h"
#include "viosfm/scene/features.h"
#include "viosfm/util/types.h"

namespace viosfm {

// A frame's most similar earlier frames.
struct RetrievedFrame {
  image_t image_id = kInvalidImageId;
  std::vector<ImageScore> similar;  // best first, at most num_neighbors, each score > 0
};

class IncrementalRetrieval {
 public:
  // options.num_neighbors (N2) similar frames per frame; InputError for a
  // vocabulary file that cannot be read. CHECKs num_training_frames >= 1
  // and num_temporal_neighbors >= 0.
  IncrementalRetrieval(const RetrievalOptions& options, int num_training_frames,
                       int num_temporal_neighbors);
  ~IncrementalRetrieval();

  // Adds the next frame. Returns the frames whose retrieval is done now, in
  // order: this one, none while the vocabulary waits for its training
  // frames, or every waiting frame once it is trained. InputError for
  // descriptors of another length than the vocabulary's.
  std::vector<RetrievedFrame> Add(image_t image_id, const FeatureDescriptors& descriptors);
  // No more frames: the waiting frames' retrieval (the vocabulary trained on
  // what came).
  std::vector<RetrievedFrame> Finish();

  size_t num_frames() const { return frame_ids_.size(); }
  bool has_vocabulary() const { return vocabulary_ != nullptr; }

 private:
  struct Entry {
    int32_t word;
    float weight;
  };
  struct Posting {
    int32_t frame;
    float weight;
  };
  void TrainOnWaitingFrames();
  std::vector<int32_t> Quantize(image_t image_id, const FeatureDescriptors& descriptors) const;
  // Indexes frame `frame` (its words) and returns its retrieval among the
  // frames indexed before it.
  RetrievedFrame IndexAndQuery(size_t frame, const std::vector<int32_t>& words);
  std::vector<RetrievedFrame> RetrieveWaiting();

  RetrievalOptions options_;
  int num_training_frames_;
  int num_temporal_neighbors_;
  std::unique_ptr<VocabularyTree> vocabulary_;
  std::vector<float> idf_;
  std::vector<image_t> frame_ids_;  // every frame, in order
  // Frames waiting for the vocabulary: their descriptors.
  std::vector<FeatureDescriptors> waiting_;
  std::vector<std::vector<Posting>> postings_;  // per word
};

}  // namespace viosfm

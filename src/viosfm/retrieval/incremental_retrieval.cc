#include "viosfm/retrieval/incremental_retrieval.h"

#include <algorithm>
#include <cmath>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

// Sorted by word, repeats merged: (word, count).
template <class Entry>
std::vector<Entry> Histogram(std::vector<int32_t> words) {
  std::sort(words.begin(), words.end());
  std::vector<Entry> histogram;
  for (const int32_t word : words) {
    if (!histogram.empty() && histogram.back().word == word) {
      histogram.back().weight += 1.0f;
    } else {
      histogram.push_back({word, 1.0f});
    }
  }
  return histogram;
}

}  // namespace

IncrementalRetrieval::IncrementalRetrieval(const RetrievalOptions& options, int num_training_frames,
                                           int num_temporal_neighbors)
    : options_(options),
      num_training_frames_(num_training_frames),
      num_temporal_neighbors_(num_temporal_neighbors) {
  VIOSFM_CHECK(options_.Check()) << options_.Validate();
  VIOSFM_CHECK_GE(num_training_frames_, 1);
  VIOSFM_CHECK_GE(num_temporal_neighbors_, 0);
  if (!options_.vocabulary_path.empty()) {
    vocabulary_ = std::make_unique<VocabularyTree>(VocabularyTree::Load(options_.vocabulary_path));
  }
}

IncrementalRetrieval::~IncrementalRetrieval() = default;

std::vector<int32_t> IncrementalRetrieval::Quantize(image_t image_id,
                                                    const FeatureDescriptors& descriptors) const {
  if (descriptors.rows() == 0) return {};
  if (descriptors.cols() != vocabulary_->descriptor_dim()) {
    throw InputError(options_.vocabulary_path, 0,
                     "the vocabulary has descriptors of " +
                         std::to_string(vocabulary_->descriptor_dim()) + " values, image " +
                         std::to_string(image_id) + " has " + std::to_string(descriptors.cols()));
  }
  return vocabulary_->Quantize(descriptors, options_.num_threads);
}

void IncrementalRetrieval::TrainOnWaitingFrames() {
  if (vocabulary_ == nullptr) {
    VocabularyTreeOptions training = options_.vocabulary;
    training.num_threads = options_.num_threads;
    vocabulary_ = std::make_unique<VocabularyTree>(TrainVocabularyTree(
        waiting_.size(), [this](size_t index) { return waiting_[index]; }, training));
  }
  VIOSFM_CHECK(!vocabulary_->empty()) << "empty vocabulary tree";
  postings_.assign(static_cast<size_t>(vocabulary_->num_words()), {});
}

std::vector<RetrievedFrame> IncrementalRetrieval::RetrieveWaiting() {
  const size_t first = frame_ids_.size() - waiting_.size();
  std::vector<std::vector<int32_t>> words;
  words.reserve(waiting_.size());
  for (size_t k = 0; k < waiting_.size(); ++k) {
    words.push_back(Quantize(frame_ids_[first + k], waiting_[k]));
  }
  waiting_.clear();
  waiting_.shrink_to_fit();
  if (idf_.empty()) {
    // The inverse document frequencies of the frames so far (the training
    // frames, or with a vocabulary file the first frames), kept from now on.
    std::vector<int64_t> document_frequency(postings_.size(), 0);
    for (const std::vector<int32_t>& frame_words : words) {
      for (const Entry& entry : Histogram<Entry>(frame_words)) ++document_frequency[entry.word];
    }
    idf_.assign(postings_.size(), 0.0f);
    const double num_frames = static_cast<double>(words.size());
    for (size_t word = 0; word < postings_.size(); ++word) {
      if (document_frequency[word] > 0) {
        idf_[word] = static_cast<float>(std::log(num_frames / document_frequency[word]));
      }
    }
  }
  std::vector<RetrievedFrame> retrieved;
  for (size_t k = 0; k < words.size(); ++k) retrieved.push_back(IndexAndQuery(first + k, words[k]));
  return retrieved;
}

RetrievedFrame IncrementalRetrieval::IndexAndQuery(size_t frame,
                                                   const std::vector<int32_t>& words) {
  std::vector<Entry> vector = Histogram<Entry>(words);
  double total = 0.0;
  for (Entry& entry : vector) {
    entry.weight *= idf_[entry.word];
    total += entry.weight;
  }
  if (total > 0.0) {
    const float scale = static_cast<float>(1.0 / total);
    for (Entry& entry : vector) entry.weight *= scale;
  }
  RetrievedFrame result;
  result.image_id = frame_ids_[frame];
  // Candidates: the frames before the temporal window.
  const size_t candidates_end =
      frame > static_cast<size_t>(num_temporal_neighbors_) ? frame - num_temporal_neighbors_ : 0;
  if (candidates_end > 0 && options_.num_neighbors > 0) {
    std::vector<float> scores(candidates_end, 0.0f);
    for (const Entry& entry : vector) {
      if (entry.weight <= 0.0f) continue;
      for (const Posting& posting : postings_[entry.word]) {
        if (static_cast<size_t>(posting.frame) >= candidates_end) break;  // by frame
        scores[posting.frame] += std::min(entry.weight, posting.weight);
      }
    }
    for (size_t c = 0; c < candidates_end; ++c) {
      if (scores[c] > 0.0f) result.similar.push_back({frame_ids_[c], std::min(scores[c], 1.0f)});
    }
    const auto better = [](const ImageScore& a, const ImageScore& b) {
      return a.score != b.score ? a.score > b.score : a.image_id < b.image_id;
    };
    const size_t count =
        std::min(result.similar.size(), static_cast<size_t>(options_.num_neighbors));
    std::partial_sort(result.similar.begin(), result.similar.begin() + count, result.similar.end(),
                      better);
    result.similar.resize(count);
  }
  for (const Entry& entry : vector) {
    if (entry.weight > 0.0f) {
      postings_[entry.word].push_back({static_cast<int32_t>(frame), entry.weight});
    }
  }
  return result;
}

std::vector<RetrievedFrame> IncrementalRetrieval::Add(image_t image_id,
                                                      const FeatureDescriptors& descriptors) {
  frame_ids_.push_back(image_id);
  if (!idf_.empty()) {
    return {IndexAndQuery(frame_ids_.size() - 1, Quantize(image_id, descriptors))};
  }
  waiting_.push_back(descriptors);
  if (waiting_.size() < static_cast<size_t>(num_training_frames_)) return {};
  TrainOnWaitingFrames();
  return RetrieveWaiting();
}

std::vector<RetrievedFrame> IncrementalRetrieval::Finish() {
  if (waiting_.empty()) return {};
  TrainOnWaitingFrames();
  return RetrieveWaiting();
}

}  // namespace viosfm

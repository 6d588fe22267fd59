#include "viosfm/retrieval/inverted_index.h"

#include <algorithm>
#include <cmath>

#include "viosfm/util/errors.h"

namespace viosfm {

InvertedIndex::InvertedIndex(int num_words) : num_words_(num_words) {
  VIOSFM_CHECK_GE(num_words, 1);
}

std::vector<InvertedIndex::Entry> InvertedIndex::Histogram(
    const std::vector<int32_t>& words) const {
  std::vector<int32_t> sorted = words;
  std::sort(sorted.begin(), sorted.end());
  std::vector<Entry> histogram;
  for (const int32_t word : sorted) {
    VIOSFM_CHECK(word >= 0 && word < num_words_) << "word " << word << " of " << num_words_;
    if (!histogram.empty() && histogram.back().word == word) {
      histogram.back().weight += 1.0f;
    } else {
      histogram.push_back({word, 1.0f});
    }
  }
  return histogram;
}

void InvertedIndex::Weight(std::vector<Entry>* vector) const {
  double total = 0.0;
  for (Entry& entry : *vector) {
    entry.weight *= idf_[entry.word];
    total += entry.weight;
  }
  if (total <= 0.0) return;
  const float scale = static_cast<float>(1.0 / total);
  for (Entry& entry : *vector) entry.weight *= scale;
}

void InvertedIndex::AddImage(image_t image_id, const std::vector<int32_t>& words) {
  VIOSFM_CHECK(!finalized_) << "AddImage after Finalize";
  std::vector<Entry> histogram = Histogram(words);
  VIOSFM_CHECK(index_of_image_.emplace(image_id, static_cast<int32_t>(image_ids_.size())).second)
      << "image " << image_id << " added twice";
  image_ids_.push_back(image_id);
  vectors_.push_back(std::move(histogram));
}

void InvertedIndex::Finalize() {
  VIOSFM_CHECK(!finalized_) << "Finalize called twice";
  std::vector<int64_t> document_frequency(num_words_, 0);
  for (const std::vector<Entry>& vector : vectors_) {
    for (const Entry& entry : vector) ++document_frequency[entry.word];
  }
  const double num_images = static_cast<double>(image_ids_.size());
  idf_.assign(num_words_, 0.0f);
  for (int word = 0; word < num_words_; ++word) {
    if (document_frequency[word] > 0) {
      idf_[word] = static_cast<float>(std::log(num_images / document_frequency[word]));
    }
  }
  postings_.assign(num_words_, {});
  for (int word = 0; word < num_words_; ++word) postings_[word].reserve(document_frequency[word]);
  for (size_t index = 0; index < vectors_.size(); ++index) {
    Weight(&vectors_[index]);
    for (const Entry& entry : vectors_[index]) {
      if (entry.weight > 0.0f) {
        postings_[entry.word].push_back({static_cast<int32_t>(index), entry.weight});
      }
    }
  }
  finalized_ = true;
}

std::vector<ImageScore> InvertedIndex::Query(image_t image_id, int k,
                                             const std::unordered_set<image_t>& exclude) const {
  VIOSFM_CHECK(finalized_) << "Query before Finalize";
  const auto it = index_of_image_.find(image_id);
  VIOSFM_CHECK(it != index_of_image_.end()) << "image " << image_id << " is not in the index";
  return Score(vectors_[it->second], k, exclude, image_id);
}

std::vector<ImageScore> InvertedIndex::QueryWords(
    const std::vector<int32_t>& words, int k, const std::unordered_set<image_t>& exclude) const {
  VIOSFM_CHECK(finalized_) << "Query before Finalize";
  std::vector<Entry> query = Histogram(words);
  Weight(&query);
  return Score(query, k, exclude, kInvalidImageId);
}

std::vector<ImageScore> InvertedIndex::Score(const std::vector<Entry>& query, int k,
                                             const std::unordered_set<image_t>& exclude,
                                             image_t self) const {
  if (k <= 0) return {};
  std::vector<float> scores(image_ids_.size(), 0.0f);
  for (const Entry& entry : query) {
    if (entry.weight <= 0.0f) continue;
    for (const Posting& posting : postings_[entry.word]) {
      scores[posting.image_index] += std::min(entry.weight, posting.weight);
    }
  }
  std::vector<ImageScore> candidates;
  for (size_t index = 0; index < scores.size(); ++index) {
    const image_t candidate = image_ids_[index];
    if (scores[index] <= 0.0f || candidate == self || exclude.count(candidate) > 0) continue;
    candidates.push_back({candidate, std::min(scores[index], 1.0f)});
  }
  const auto better = [](const ImageScore& a, const ImageScore& b) {
    return a.score != b.score ? a.score > b.score : a.image_id < b.image_id;
  };
  const size_t count = std::min(candidates.size(), static_cast<size_t>(k));
  std::partial_sort(candidates.begin(), candidates.begin() + count, candidates.end(), better);
  candidates.resize(count);
  return candidates;
}

}  // namespace viosfm

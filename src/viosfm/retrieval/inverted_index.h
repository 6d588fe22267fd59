// Inverted file with TF-IDF weighting for image retrieval (Nister &
// Stewenius 2006).
//
// Each database image becomes a vector over the visual words: v_w = tf_w *
// idf_w, tf_w = the number of the image's descriptors quantised to w,
// idf_w = ln(N / N_w) with N database images and N_w of them containing w;
// the vector is L1-normalised. The similarity of a query q and an image d is
//   score = 1 - ||q - d||_1 / 2 = sum_w min(q_w, d_w)   (in [0, 1]),
// computed from the inverted file (per word, the images containing it and
// their weights) by visiting only the words the query contains.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "viosfm/util/types.h"

namespace viosfm {

struct ImageScore {
  image_t image_id = kInvalidImageId;
  float score = 0.0f;  // 1 - ||q - d||_1 / 2, in [0, 1]; higher is more similar
};

class InvertedIndex {
 public:
  explicit InvertedIndex(int num_words);

  // Adds a database image by the visual words of its descriptors (any order,
  // repeats counted). Throws InternalError for a repeated image id, a word
  // outside [0, num_words) or after Finalize().
  void AddImage(image_t image_id, const std::vector<int32_t>& words);
  // Computes the idf weights and the normalised vectors; then the index is
  // read-only and the Query functions may be called, also concurrently.
  void Finalize();

  // The database images most similar to database image `image_id`, best
  // first (ties by increasing id), at most `k`, only with a score > 0,
  // leaving out `image_id` itself and every id in `exclude`.
  std::vector<ImageScore> Query(image_t image_id, int k,
                                const std::unordered_set<image_t>& exclude = {}) const;
  // The same for a query image given by its words (not necessarily in the database).
  std::vector<ImageScore> QueryWords(const std::vector<int32_t>& words, int k,
                                     const std::unordered_set<image_t>& exclude = {}) const;

  int num_words() const { return num_words_; }
  int64_t num_images() const { return static_cast<int64_t>(image_ids_.size()); }
  bool finalized() const { return finalized_; }
  bool Contains(image_t image_id) const { return index_of_image_.count(image_id) > 0; }
  // idf of every word (after Finalize()); 0 for words in no or in every image.
  const std::vector<float>& idf() const { return idf_; }

 private:
  struct Entry {
    int32_t word;
    float weight;
  };
  // Sorted by word, repeats merged: (word, count).
  std::vector<Entry> Histogram(const std::vector<int32_t>& words) const;
  // Histogram -> TF-IDF weights, L1-normalised (all zero if no word has weight).
  void Weight(std::vector<Entry>* vector) const;
  std::vector<ImageScore> Score(const std::vector<Entry>& query, int k,
                                const std::unordered_set<image_t>& exclude, image_t self) const;

  int num_words_;
  bool finalized_ = false;
  std::vector<image_t> image_ids_;                       // in insertion order
  std::unordered_map<image_t, int32_t> index_of_image_;  // image id -> insertion index
  std::vector<std::vector<Entry>> vectors_;              // per image: counts, then weights
  std::vector<float> idf_;
  struct Posting {
    int32_t image_index;
    float weight;
  };
  std::vector<std::vector<Posting>> postings_;  // per word
};

}  // namespace viosfm

// Image retrieval for the paper's N2 visually similar images: a vocabulary
// tree (trained on the sequence's own descriptors, or loaded from a file),
// an inverted file with TF-IDF scoring, and per image the N2 best other
// images outside its exclusion set (itself and its N1 temporal neighbours,
// which the pair generator adds anyway).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/retrieval/inverted_index.h"
#include "viosfm/retrieval/vocabulary_tree.h"
#include "viosfm/scene/features.h"
#include "viosfm/util/types.h"

namespace viosfm {

struct RetrievalOptions {
  int num_neighbors = 30;            // N2: retrieved images per image (paper: 30), >= 1
  VocabularyTreeOptions vocabulary;  // tree training (branching 10, depth 4, 200k descriptors)
  // If non-empty, the tree is loaded from this file (io/vocabulary_io.h)
  // instead of trained on the images. Default: empty (train).
  std::string vocabulary_path;
  int num_threads = -1;  // worker threads for everything, also training (<= 0: all)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// For every image, in the order of `image_ids`: up to num_neighbors other
// images, best first, with a score > 0, none of them the image itself or in
// exclude[i] (`exclude` is empty or has one list per image). `load` gives
// the descriptors of image_ids[index]; it is called once per image (twice
// when the tree is trained here: one pass samples training descriptors).
// The tree is, in order of precedence: `vocabulary` if not null, else the
// file options.vocabulary_path if set, else trained on these images.
// Deterministic for a given seed, whatever the number of threads.
std::vector<std::vector<ImageScore>> RetrieveSimilarImageScores(
    const std::vector<image_t>& image_ids, const DescriptorLoader& load,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary = nullptr);

// The same, image ids only.
std::vector<std::vector<image_t>> RetrieveSimilarImages(
    const std::vector<image_t>& image_ids, const DescriptorLoader& load,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary = nullptr);

// Convenience: descriptors in memory, descriptors[i] belonging to image_ids[i].
std::vector<std::vector<image_t>> RetrieveSimilarImages(
    const std::vector<image_t>& image_ids, const std::vector<FeatureDescriptors>& descriptors,
    const std::vector<std::vector<image_t>>& exclude, const RetrievalOptions& options,
    const VocabularyTree* vocabulary = nullptr);

// Per image, the images at most `window` positions away in `image_ids`
// (not itself): the exclusion sets for a temporal window of that radius.
std::vector<std::vector<image_t>> TemporalNeighborExclusion(const std::vector<image_t>& image_ids,
                                                            int window);

}  // namespace viosfm

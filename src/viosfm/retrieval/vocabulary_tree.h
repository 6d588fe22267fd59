// Vocabulary tree (Nister & Stewenius, "Scalable recognition with a
// vocabulary tree", CVPR 2006): hierarchical k-means on descriptors; a
// descriptor's visual word is the leaf reached by descending greedily to the
// nearest child centre at every level.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "viosfm/retrieval/kmeans.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/vocabulary_data.h"

namespace viosfm {

struct VocabularyTreeOptions {
  int branching = 10;  // children per node (k of each k-means), >= 2
  int depth = 4;       // levels below the root, >= 1: at most branching^depth words (10^4)
  // Training uses a seeded random subsample of at most this many descriptors.
  int max_training_descriptors = 200000;
  int kmeans_iterations = 10;  // Lloyd iterations per node, >= 1
  uint64_t seed = 0;           // seeds the subsampling and every node's k-means++
  int num_threads = -1;        // worker threads (<= 0: all hardware threads)

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Descriptors of the index-th image, index in [0, num_images). Called from
// one thread at a time, in increasing index order.
using DescriptorLoader = std::function<FeatureDescriptors(size_t index)>;

class VocabularyTree {
 public:
  VocabularyTree() = default;
  // Throws InternalError if data.Validate() fails.
  explicit VocabularyTree(VocabularyData data);

  // Hierarchical k-means on all rows of `descriptors` (no subsampling).
  // The tree depends on options.seed only, not on num_threads.
  static VocabularyTree Train(const FloatDescriptors& descriptors,
                              const VocabularyTreeOptions& options);

  // Through io/vocabulary_io.h; Load throws InputError for a bad file.
  static VocabularyTree Load(const std::filesystem::path& path);
  void Save(const std::filesystem::path& path) const;

  bool empty() const { return data_.num_nodes() == 0; }
  int num_words() const { return data_.num_words; }
  int descriptor_dim() const { return data_.descriptor_dim; }
  int64_t num_nodes() const { return data_.num_nodes(); }
  const VocabularyData& data() const { return data_; }

  // Visual word of one descriptor of descriptor_dim() floats.
  int32_t Quantize(const float* descriptor) const;
  // Visual word of every row; throws InternalError if the column count differs
  // from descriptor_dim().
  std::vector<int32_t> Quantize(const FloatDescriptors& descriptors, int num_threads = 1) const;
  std::vector<int32_t> Quantize(const FeatureDescriptors& descriptors, int num_threads = 1) const;

 private:
  VocabularyData data_;
};

FloatDescriptors DescriptorsToFloat(const FeatureDescriptors& descriptors);

// A seeded random subsample of the images' descriptors: from each image at
// most ceil(max_training_descriptors / num_images) of its rows, so at most
// max_training_descriptors in total.
FloatDescriptors SampleTrainingDescriptors(size_t num_images, const DescriptorLoader& load,
                                           const VocabularyTreeOptions& options);

// SampleTrainingDescriptors, then VocabularyTree::Train, with a log line.
VocabularyTree TrainVocabularyTree(size_t num_images, const DescriptorLoader& load,
                                   const VocabularyTreeOptions& options);

}  // namespace viosfm

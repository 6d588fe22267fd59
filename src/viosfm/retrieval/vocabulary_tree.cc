#include "viosfm/retrieval/vocabulary_tree.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "viosfm/io/vocabulary_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/random.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// Descriptors quantised per parallel chunk.
constexpr int64_t kQuantizeChunk = 512;

// SplitMix64 mixing of (seed, value), for deriving independent seeds.
uint64_t DeriveSeed(uint64_t seed, uint64_t value) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (value + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

std::string VocabularyTreeOptions::Validate() const {
  if (branching < 2) return "branching must be >= 2";
  if (depth < 1) return "depth must be >= 1";
  if (std::pow(static_cast<double>(branching), depth) > std::numeric_limits<int32_t>::max()) {
    return "branching^depth must fit in int32";
  }
  if (max_training_descriptors < 1) return "max_training_descriptors must be >= 1";
  if (kmeans_iterations < 1) return "kmeans_iterations must be >= 1";
  return "";
}

VocabularyTree::VocabularyTree(VocabularyData data) : data_(std::move(data)) {
  const std::string problem = data_.Validate();
  VIOSFM_CHECK(problem.empty()) << "inconsistent vocabulary: " << problem;
}

VocabularyTree VocabularyTree::Train(const FloatDescriptors& descriptors,
                                     const VocabularyTreeOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK_GT(descriptors.cols(), 0);
  VIOSFM_CHECK_LE(descriptors.rows(), std::numeric_limits<int32_t>::max());
  const int dim = static_cast<int>(descriptors.cols());
  VocabularyData data;
  data.branching = options.branching;
  data.depth = options.depth;
  data.descriptor_dim = dim;

  auto add_node = [&data, dim](const float* center) {
    data.first_child.push_back(-1);
    data.num_children.push_back(0);
    data.word_of_node.push_back(-1);
    if (center == nullptr) {
      data.centers.insert(data.centers.end(), dim, 0.0f);
    } else {
      data.centers.insert(data.centers.end(), center, center + dim);
    }
    return static_cast<int32_t>(data.first_child.size() - 1);
  };

  struct Pending {
    int32_t node;
    int level;
    std::vector<int32_t> rows;
  };
  const auto is_leaf = [&options](const Pending& pending) {
    return pending.level == options.depth ||
           static_cast<int64_t>(pending.rows.size()) < options.branching;
  };
  std::vector<int32_t> all_rows(descriptors.rows());
  std::iota(all_rows.begin(), all_rows.end(), 0);
  std::vector<Pending> level_nodes;
  level_nodes.push_back({add_node(nullptr), 0, std::move(all_rows)});
  // Level by level, so that every node's children get consecutive ids (breadth
  // first). A level's nodes are clustered in parallel, a single node with
  // parallel assignments; each clustering depends on its seed only.
  while (!level_nodes.empty()) {
    const bool across_nodes = level_nodes.size() > 1;
    std::vector<KMeansResult> clusters(level_nodes.size());
    ParallelFor(static_cast<int64_t>(level_nodes.size()), across_nodes ? options.num_threads : 1,
                [&](int64_t index, int /*thread_index*/) {
                  const Pending& pending = level_nodes[index];
                  if (is_leaf(pending)) return;
                  KMeansOptions kmeans;
                  kmeans.num_clusters = options.branching;
                  kmeans.max_iterations = options.kmeans_iterations;
                  kmeans.seed = DeriveSeed(options.seed, static_cast<uint64_t>(pending.node));
                  kmeans.num_threads = across_nodes ? 1 : options.num_threads;
                  clusters[index] = KMeans(descriptors, pending.rows, kmeans);
                });
    std::vector<Pending> next_level;
    for (size_t index = 0; index < level_nodes.size(); ++index) {
      Pending& pending = level_nodes[index];
      const int k = static_cast<int>(clusters[index].centers.rows());
      if (is_leaf(pending) || k < 2) {  // k < 2: all descriptors identical, nothing to split
        data.word_of_node[pending.node] = data.num_words++;
        continue;
      }
      std::vector<std::vector<int32_t>> child_rows(k);
      for (size_t i = 0; i < pending.rows.size(); ++i) {
        child_rows[clusters[index].labels[i]].push_back(pending.rows[i]);
      }
      pending.rows = {};
      data.first_child[pending.node] = static_cast<int32_t>(data.num_nodes());
      data.num_children[pending.node] = k;
      for (int c = 0; c < k; ++c) {
        const int32_t child = add_node(clusters[index].centers.row(c).data());
        next_level.push_back({child, pending.level + 1, std::move(child_rows[c])});
      }
    }
    level_nodes = std::move(next_level);
  }
  return VocabularyTree(std::move(data));
}

VocabularyTree VocabularyTree::Load(const std::filesystem::path& path) {
  return VocabularyTree(ReadVocabulary(path));
}

void VocabularyTree::Save(const std::filesystem::path& path) const {
  WriteVocabulary(path, data_);
}

int32_t VocabularyTree::Quantize(const float* descriptor) const {
  VIOSFM_CHECK(!empty()) << "quantising with an empty vocabulary tree";
  const int dim = data_.descriptor_dim;
  const Eigen::Map<const Eigen::VectorXf> query(descriptor, dim);
  int32_t node = 0;
  while (data_.num_children[node] > 0) {
    const int32_t first = data_.first_child[node];
    int32_t best = first;
    float best_distance = std::numeric_limits<float>::infinity();
    for (int32_t child = first; child < first + data_.num_children[node]; ++child) {
      const Eigen::Map<const Eigen::VectorXf> center(
          data_.centers.data() + static_cast<size_t>(child) * dim, dim);
      const float distance = (query - center).squaredNorm();
      if (distance < best_distance) {
        best_distance = distance;
        best = child;
      }
    }
    node = best;
  }
  return data_.word_of_node[node];
}

std::vector<int32_t> VocabularyTree::Quantize(const FloatDescriptors& descriptors,
                                              int num_threads) const {
  VIOSFM_CHECK_EQ(descriptors.cols(), data_.descriptor_dim);
  std::vector<int32_t> words(descriptors.rows());
  ParallelForChunks(descriptors.rows(), num_threads, kQuantizeChunk,
                    [&](int64_t begin, int64_t end) {
                      for (int64_t i = begin; i < end; ++i)
                        words[i] = Quantize(descriptors.row(i).data());
                    });
  return words;
}

std::vector<int32_t> VocabularyTree::Quantize(const FeatureDescriptors& descriptors,
                                              int num_threads) const {
  return Quantize(DescriptorsToFloat(descriptors), num_threads);
}

FloatDescriptors DescriptorsToFloat(const FeatureDescriptors& descriptors) {
  return descriptors.cast<float>();
}

FloatDescriptors SampleTrainingDescriptors(size_t num_images, const DescriptorLoader& load,
                                           const VocabularyTreeOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  if (num_images == 0) return FloatDescriptors();
  const int64_t quota =
      (static_cast<int64_t>(options.max_training_descriptors) + num_images - 1) / num_images;
  std::vector<FloatDescriptors> sampled(num_images);
  int64_t total = 0;
  int dim = -1;
  ProgressBar progress("Sampling training descriptors", static_cast<int64_t>(num_images));
  for (size_t index = 0; index < num_images; ++index) {
    const FeatureDescriptors descriptors = load(index);
    progress.Update();
    if (descriptors.rows() == 0) continue;
    if (dim < 0) dim = static_cast<int>(descriptors.cols());
    VIOSFM_CHECK_EQ(descriptors.cols(), dim) << "image " << index << " has another descriptor size";
    std::vector<int32_t> rows(descriptors.rows());
    std::iota(rows.begin(), rows.end(), 0);
    if (static_cast<int64_t>(rows.size()) > quota) {
      // Partial Fisher-Yates: the first `quota` entries become a uniform subset.
      Random random(DeriveSeed(options.seed, index));
      for (int64_t i = 0; i < quota; ++i) {
        std::swap(rows[i], rows[random.UniformInt(i, static_cast<int64_t>(rows.size()) - 1)]);
      }
      rows.resize(quota);
      std::sort(rows.begin(), rows.end());
    }
    FloatDescriptors& out = sampled[index];
    out.resize(static_cast<int64_t>(rows.size()), dim);
    for (size_t i = 0; i < rows.size(); ++i) out.row(i) = descriptors.row(rows[i]).cast<float>();
    total += out.rows();
  }
  progress.Finish();
  FloatDescriptors training(total, std::max(dim, 0));
  int64_t offset = 0;
  for (const FloatDescriptors& part : sampled) {
    if (part.rows() == 0) continue;
    training.middleRows(offset, part.rows()) = part;
    offset += part.rows();
  }
  return training;
}

VocabularyTree TrainVocabularyTree(size_t num_images, const DescriptorLoader& load,
                                   const VocabularyTreeOptions& options) {
  const FloatDescriptors training = SampleTrainingDescriptors(num_images, load, options);
  if (training.rows() == 0) {
    throw InputError("cannot train a vocabulary tree: the " + std::to_string(num_images) +
                     " images have no descriptors");
  }
  Timer timer;
  VocabularyTree tree = VocabularyTree::Train(training, options);
  VIOSFM_LOG(INFO) << "Trained a vocabulary tree (branching " << options.branching << ", depth "
                   << options.depth << ") on " << training.rows()
                   << " descriptors: " << tree.num_words() << " words, " << timer.ElapsedSeconds()
                   << " s";
  return tree;
}

}  // namespace viosfm

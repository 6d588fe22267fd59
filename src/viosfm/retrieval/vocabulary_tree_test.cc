#include "viosfm/retrieval/vocabulary_tree.h"

#include <gtest/gtest.h>

#include <set>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

constexpr int kDim = 128;

// Two-level structure: 4 groups far apart (centres uniform in [0, 200] per
// axis), each with 4 clusters (offsets uniform in [-15, 15] per axis),
// points with spread 1 around their cluster centre. truth[i] = 4 * group +
// cluster of row i; rows are interleaved.
FloatDescriptors TwoLevelBlobs(int per_cluster, uint64_t seed, std::vector<int>* truth) {
  Random random(seed);
  FloatDescriptors centers(16, kDim);
  for (int group = 0; group < 4; ++group) {
    Eigen::RowVectorXf group_center(kDim);
    for (int d = 0; d < kDim; ++d) group_center[d] = static_cast<float>(random.Uniform(0, 200));
    for (int cluster = 0; cluster < 4; ++cluster) {
      for (int d = 0; d < kDim; ++d) {
        centers(4 * group + cluster, d) =
            group_center[d] + static_cast<float>(random.Uniform(-15, 15));
      }
    }
  }
  FloatDescriptors points(16 * per_cluster, kDim);
  truth->clear();
  for (int i = 0; i < per_cluster; ++i) {
    for (int c = 0; c < 16; ++c) {
      const int row = static_cast<int>(truth->size());
      for (int d = 0; d < kDim; ++d) {
        points(row, d) = centers(c, d) + static_cast<float>(random.Normal(0.0, 1.0));
      }
      truth->push_back(c);
    }
  }
  return points;
}

VocabularyTreeOptions SmallOptions() {
  VocabularyTreeOptions options;
  options.branching = 4;
  options.depth = 2;
  options.seed = 42;
  options.num_threads = 1;
  return options;
}

TEST(VocabularyTree, HierarchicalKMeansRecoversNestedClusters) {
  std::vector<int> truth;
  const FloatDescriptors points = TwoLevelBlobs(40, /*seed=*/1, &truth);
  const VocabularyTree tree = VocabularyTree::Train(points, SmallOptions());
  EXPECT_EQ(tree.num_words(), 16);
  EXPECT_EQ(tree.num_nodes(), 1 + 4 + 16);
  EXPECT_EQ(tree.data().Validate(), "");
  // Every training vector lands on its cluster's word, one word per cluster.
  const std::vector<int32_t> words = tree.Quantize(points);
  std::vector<int32_t> word_of_cluster(16, -1);
  for (size_t i = 0; i < truth.size(); ++i) {
    if (word_of_cluster[truth[i]] < 0) word_of_cluster[truth[i]] = words[i];
    EXPECT_EQ(words[i], word_of_cluster[truth[i]]) << "row " << i;
  }
  EXPECT_EQ(std::set<int32_t>(word_of_cluster.begin(), word_of_cluster.end()).size(), 16u);
  // Clusters of one group share a level-1 node: word ids are assigned
  // breadth first, so the group's 4 words are consecutive.
  for (int group = 0; group < 4; ++group) {
    std::set<int32_t> group_words(word_of_cluster.begin() + 4 * group,
                                  word_of_cluster.begin() + 4 * group + 4);
    EXPECT_EQ(*group_words.rbegin() - *group_words.begin(), 3) << "group " << group;
  }
  // A new vector drawn from a cluster quantises to that cluster's word.
  Eigen::RowVectorXf query = points.row(5);
  query += Eigen::RowVectorXf::Constant(kDim, 0.5f);
  EXPECT_EQ(tree.Quantize(query.data()), word_of_cluster[truth[5]]);
}

TEST(VocabularyTree, DeterministicPerSeedAndIndependentOfThreads) {
  std::vector<int> truth;
  FloatDescriptors points = TwoLevelBlobs(60, /*seed=*/2, &truth);
  VocabularyTreeOptions options = SmallOptions();
  options.depth = 3;
  const VocabularyTree a = VocabularyTree::Train(points, options);
  options.num_threads = 2;
  const VocabularyTree b = VocabularyTree::Train(points, options);
  EXPECT_EQ(a.data().centers, b.data().centers);
  EXPECT_EQ(a.data().first_child, b.data().first_child);
  EXPECT_EQ(a.data().word_of_node, b.data().word_of_node);
  EXPECT_EQ(a.Quantize(points, 1), b.Quantize(points, 2));
  options.seed = 43;
  const VocabularyTree c = VocabularyTree::Train(points, options);
  EXPECT_NE(a.data().centers, c.data().centers);
}

TEST(VocabularyTree, SmallNodesBecomeLeaves) {
  FloatDescriptors points(3, kDim);
  points.setRandom();
  VocabularyTreeOptions options = SmallOptions();  // branching 4 > 3 points
  const VocabularyTree tree = VocabularyTree::Train(points, options);
  EXPECT_EQ(tree.num_words(), 1);
  EXPECT_EQ(tree.num_nodes(), 1);
  EXPECT_EQ(tree.Quantize(points.row(2).data()), 0);
}

TEST(VocabularyTree, SaveLoadGivesTheSameTree) {
  std::vector<int> truth;
  const FloatDescriptors points = TwoLevelBlobs(20, /*seed=*/3, &truth);
  const VocabularyTree tree = VocabularyTree::Train(points, SmallOptions());
  const auto path = testing::MakeScratchFolder("vocabulary_tree") / "tree.bin";
  tree.Save(path);
  const VocabularyTree loaded = VocabularyTree::Load(path);
  EXPECT_EQ(loaded.data().centers, tree.data().centers);
  EXPECT_EQ(loaded.data().num_children, tree.data().num_children);
  EXPECT_EQ(loaded.Quantize(points), tree.Quantize(points));
  EXPECT_THROW(VocabularyTree::Load(path.parent_path() / "missing.bin"), InputError);
}

TEST(VocabularyTree, QuantizesUint8Descriptors) {
  Random random(4);
  FeatureDescriptors descriptors(200, kDim);
  for (int i = 0; i < descriptors.rows(); ++i) {
    for (int d = 0; d < kDim; ++d)
      descriptors(i, d) = static_cast<uint8_t>(random.UniformInt(0, 255));
  }
  VocabularyTreeOptions options = SmallOptions();
  const VocabularyTree tree = VocabularyTree::Train(DescriptorsToFloat(descriptors), options);
  const std::vector<int32_t> words = tree.Quantize(descriptors, 2);
  ASSERT_EQ(words.size(), 200u);
  for (int i = 0; i < descriptors.rows(); ++i) {
    const Eigen::RowVectorXf row = descriptors.row(i).cast<float>();
    EXPECT_EQ(words[i], tree.Quantize(row.data()));
  }
  EXPECT_THROW(tree.Quantize(FloatDescriptors(2, 64)), InternalError);
}

TEST(SampleTrainingDescriptors, CapsPerImageAndIsDeterministic) {
  std::vector<FeatureDescriptors> images;
  for (int i = 0; i < 4; ++i) {
    FeatureDescriptors descriptors(10 + 20 * i, 4);
    for (int r = 0; r < descriptors.rows(); ++r) descriptors.row(r).setConstant(10 * i + r % 10);
    images.push_back(descriptors);
  }
  const DescriptorLoader load = [&images](size_t index) { return images[index]; };
  VocabularyTreeOptions options;
  options.max_training_descriptors = 60;  // 15 per image
  const FloatDescriptors a = SampleTrainingDescriptors(images.size(), load, options);
  EXPECT_EQ(a.rows(), 10 + 15 + 15 + 15);
  EXPECT_EQ(a.cols(), 4);
  // Image i's rows come in order and hold values 10 i .. 10 i + 9.
  EXPECT_EQ(a(0, 0), 0.0f);
  EXPECT_GE(a(10, 0), 10.0f);
  EXPECT_LT(a(24, 0), 20.0f);
  EXPECT_GE(a(25, 0), 20.0f);
  EXPECT_EQ(SampleTrainingDescriptors(images.size(), load, options), a);
  options.seed = 9;
  EXPECT_NE(SampleTrainingDescriptors(images.size(), load, options), a);
}

TEST(VocabularyTreeOptions, ValidateNamesTheField) {
  VocabularyTreeOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.branching = 1;
  EXPECT_NE(options.Validate().find("branching"), std::string::npos);
  options = {};
  options.depth = 20;
  EXPECT_NE(options.Validate().find("branching^depth"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

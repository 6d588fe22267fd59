#include "viosfm/retrieval/kmeans.h"

#include <gtest/gtest.h>

#include <map>
#include <numeric>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// `num_clusters` well-separated blobs (centres 100 apart per axis in
// expectation, spread 1) of `per_cluster` points in `dim` dimensions, the
// points of a blob interleaved with the others. truth[i] = blob of row i.
FloatDescriptors Blobs(int num_clusters, int per_cluster, int dim, uint64_t seed,
                       std::vector<int>* truth, FloatDescriptors* true_centers) {
  Random random(seed);
  true_centers->resize(num_clusters, dim);
  for (int c = 0; c < num_clusters; ++c) {
    for (int d = 0; d < dim; ++d)
      (*true_centers)(c, d) = static_cast<float>(random.Uniform(0, 255));
  }
  FloatDescriptors points(num_clusters * per_cluster, dim);
  truth->clear();
  for (int i = 0; i < per_cluster; ++i) {
    for (int c = 0; c < num_clusters; ++c) {
      const int row = static_cast<int>(truth->size());
      for (int d = 0; d < dim; ++d) {
        points(row, d) = (*true_centers)(c, d) + static_cast<float>(random.Normal(0.0, 1.0));
      }
      truth->push_back(c);
    }
  }
  return points;
}

std::vector<int32_t> AllRows(const FloatDescriptors& points) {
  std::vector<int32_t> rows(points.rows());
  std::iota(rows.begin(), rows.end(), 0);
  return rows;
}

TEST(KMeans, RecoversWellSeparatedClusters) {
  std::vector<int> truth;
  FloatDescriptors true_centers;
  const FloatDescriptors points = Blobs(8, 50, 16, /*seed=*/3, &truth, &true_centers);
  KMeansOptions options;
  options.num_clusters = 8;
  options.max_iterations = 20;
  options.seed = 11;
  const KMeansResult result = KMeans(points, AllRows(points), options);
  ASSERT_EQ(result.centers.rows(), 8);
  ASSERT_EQ(result.labels.size(), points.rows());
  // The labelling is a bijection of the true blobs.
  std::map<int, int> label_of_blob;
  std::map<int, int> blob_of_label;
  for (size_t i = 0; i < truth.size(); ++i) {
    const auto [it, inserted] = label_of_blob.emplace(truth[i], result.labels[i]);
    EXPECT_EQ(it->second, result.labels[i]) << "row " << i;
    if (inserted) {
      EXPECT_TRUE(blob_of_label.emplace(result.labels[i], truth[i]).second);
    }
  }
  EXPECT_EQ(label_of_blob.size(), 8u);
  // Each centre is its blob's mean: within 4 sigma / sqrt(50) per axis of the truth.
  for (const auto& [blob, label] : label_of_blob) {
    EXPECT_LT((result.centers.row(label) - true_centers.row(blob)).cwiseAbs().maxCoeff(), 0.6f);
  }
}

TEST(KMeans, ClustersASubsetOfRows) {
  std::vector<int> truth;
  FloatDescriptors true_centers;
  const FloatDescriptors points = Blobs(4, 30, 8, /*seed=*/5, &truth, &true_centers);
  // Only the rows of blobs 0 and 1.
  std::vector<int32_t> rows;
  for (int32_t i = 0; i < points.rows(); ++i) {
    if (truth[i] < 2) rows.push_back(i);
  }
  KMeansOptions options;
  options.num_clusters = 2;
  const KMeansResult result = KMeans(points, rows, options);
  ASSERT_EQ(result.centers.rows(), 2);
  ASSERT_EQ(result.labels.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(result.labels[i] == result.labels[0], truth[rows[i]] == truth[rows[0]]);
  }
}

TEST(KMeans, DeterministicPerSeedAndIndependentOfThreads) {
  // Structureless points, so that the seed matters; enough of them that the
  // seeding's distances and the assignment run on several threads.
  Random random(7);
  FloatDescriptors points(20000, 128);
  for (int i = 0; i < points.rows(); ++i) {
    for (int d = 0; d < points.cols(); ++d) points(i, d) = static_cast<float>(random.Normal());
  }
  KMeansOptions options;
  options.num_clusters = 10;
  options.seed = 1;
  options.num_threads = 1;
  const KMeansResult a = KMeans(points, AllRows(points), options);
  options.num_threads = 3;
  const KMeansResult b = KMeans(points, AllRows(points), options);
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.centers, b.centers);
  EXPECT_EQ(a.iterations, b.iterations);
  options.seed = 2;
  const KMeansResult c = KMeans(points, AllRows(points), options);
  EXPECT_NE(a.labels, c.labels);
}

TEST(KMeans, FewerDistinctPointsThanClusters) {
  FloatDescriptors points(6, 2);
  points << 0, 0, 0, 0, 5, 5, 5, 5, 0, 0, 5, 5;
  KMeansOptions options;
  options.num_clusters = 4;
  const KMeansResult result = KMeans(points, AllRows(points), options);
  ASSERT_EQ(result.centers.rows(), 2);  // empty clusters dropped
  EXPECT_EQ(result.labels[0], result.labels[1]);
  EXPECT_EQ(result.labels[0], result.labels[4]);
  EXPECT_EQ(result.labels[2], result.labels[5]);
  EXPECT_NE(result.labels[0], result.labels[2]);
}

TEST(KMeansOptions, ValidateNamesTheField) {
  KMeansOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.num_clusters = 0;
  EXPECT_NE(options.Validate().find("num_clusters"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

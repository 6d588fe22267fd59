#include "viosfm/retrieval/inverted_index.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

TEST(InvertedIndex, HandComputedTfIdfScore) {
  InvertedIndex index(4);
  index.AddImage(10, {0, 1, 0});
  index.AddImage(20, {2, 1});
  index.AddImage(30, {3});
  index.Finalize();
  EXPECT_FLOAT_EQ(index.idf()[0], std::log(3.0f));
  EXPECT_FLOAT_EQ(index.idf()[1], std::log(1.5f));
  // Only word 1 is shared: score = min(a_1, b_1) = a_1.
  const double a1 = std::log(1.5) / (2 * std::log(3.0) + std::log(1.5));
  const std::vector<ImageScore> result = index.Query(10, 5);
  ASSERT_EQ(result.size(), 1u);  // image 30 shares nothing, 10 is the query
  EXPECT_EQ(result[0].image_id, 20u);
  EXPECT_NEAR(result[0].score, a1, 1e-6);
  // The same from the words, and symmetric.
  const std::vector<ImageScore> by_words = index.QueryWords({1, 0, 0}, 5);
  ASSERT_EQ(by_words.size(), 2u);  // now image 10 itself is a candidate, with score 1
  EXPECT_EQ(by_words[0].image_id, 10u);
  EXPECT_NEAR(by_words[0].score, 1.0, 1e-6);
  EXPECT_EQ(by_words[1].image_id, 20u);
  EXPECT_NEAR(by_words[1].score, a1, 1e-6);
  ASSERT_EQ(index.Query(20, 5).size(), 1u);
  EXPECT_NEAR(index.Query(20, 5)[0].score, a1, 1e-6);
}

// score = 1 - ||q - d||_1 / 2 with the dense L1-normalised TF-IDF vectors.
TEST(InvertedIndex, ScoresEqualDenseL1Distance) {
  constexpr int kWords = 50;
  constexpr int kImages = 12;
  Random random(1);
  std::vector<std::vector<int32_t>> images(kImages);
  for (auto& words : images) {
    const int count = static_cast<int>(random.UniformInt(1, 40));
    for (int i = 0; i < count; ++i)
      words.push_back(static_cast<int32_t>(random.UniformInt(0, kWords - 1)));
  }
  InvertedIndex index(kWords);
  for (int i = 0; i < kImages; ++i) index.AddImage(100 + i, images[i]);
  index.Finalize();
  std::vector<Eigen::VectorXd> dense(kImages, Eigen::VectorXd::Zero(kWords));
  for (int i = 0; i < kImages; ++i) {
    for (const int32_t word : images[i]) {
      int df = 0;
      for (const auto& other : images) df += std::count(other.begin(), other.end(), word) > 0;
      dense[i][word] += std::log(static_cast<double>(kImages) / df);
    }
    if (dense[i].sum() > 0) dense[i] /= dense[i].sum();
  }
  for (int i = 0; i < kImages; ++i) {
    const std::vector<ImageScore> result = index.Query(100 + i, kImages);
    int expected_count = 0;
    for (int j = 0; j < kImages; ++j) {
      if (j == i) continue;
      const double expected = 1.0 - (dense[i] - dense[j]).lpNorm<1>() / 2.0;
      if (expected > 1e-6) ++expected_count;
      const auto it = std::find_if(result.begin(), result.end(), [j](const ImageScore& s) {
        return s.image_id == static_cast<image_t>(100 + j);
      });
      const double score = it == result.end() ? 0.0 : it->score;
      EXPECT_NEAR(score, expected, 1e-5) << i << " vs " << j;
    }
    EXPECT_EQ(static_cast<int>(result.size()), expected_count);
    for (size_t r = 1; r < result.size(); ++r) EXPECT_GE(result[r - 1].score, result[r].score);
  }
}

TEST(InvertedIndex, ExclusionAndTopK) {
  InvertedIndex index(3);
  // Images 1..5 all share word 0 with the query (image 0); 5 the most.
  index.AddImage(0, {0, 0, 0});
  for (image_t id = 1; id <= 5; ++id) {
    std::vector<int32_t> words(id, 0);
    words.insert(words.end(), 6 - id, 2);
    index.AddImage(id, words);
  }
  index.AddImage(6, {1});
  index.Finalize();
  const std::vector<ImageScore> top3 = index.Query(0, 3);
  ASSERT_EQ(top3.size(), 3u);
  EXPECT_EQ(top3[0].image_id, 5u);
  EXPECT_EQ(top3[1].image_id, 4u);
  EXPECT_EQ(top3[2].image_id, 3u);
  const std::vector<ImageScore> excluded = index.Query(0, 3, {5, 3, 6});
  ASSERT_EQ(excluded.size(), 3u);
  EXPECT_EQ(excluded[0].image_id, 4u);
  EXPECT_EQ(excluded[1].image_id, 2u);
  EXPECT_EQ(excluded[2].image_id, 1u);
  EXPECT_TRUE(index.Query(0, 0).empty());
}

TEST(InvertedIndex, TiesAreOrderedById) {
  InvertedIndex index(2);
  index.AddImage(7, {0});
  index.AddImage(3, {0});
  index.AddImage(5, {0});
  index.AddImage(9, {1});
  index.Finalize();
  const std::vector<ImageScore> result = index.Query(7, 5);
  ASSERT_EQ(result.size(), 2u);
  EXPECT_EQ(result[0].image_id, 3u);
  EXPECT_EQ(result[1].image_id, 5u);
  EXPECT_FLOAT_EQ(result[0].score, result[1].score);
}

TEST(InvertedIndex, MisuseIsAnInternalError) {
  InvertedIndex index(2);
  index.AddImage(1, {0});
  EXPECT_THROW(index.AddImage(1, {1}), InternalError);
  EXPECT_THROW(index.AddImage(2, {2}), InternalError);
  EXPECT_THROW(index.Query(1, 1), InternalError);
  index.Finalize();
  EXPECT_THROW(index.AddImage(3, {0}), InternalError);
  EXPECT_THROW(index.Query(42, 1), InternalError);
}

}  // namespace
}  // namespace viosfm

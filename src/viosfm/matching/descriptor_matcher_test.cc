#include "viosfm/matching/descriptor_matcher.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "viosfm/geometry/epipolar.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

constexpr int kDim = 128;

// A SIFT-like descriptor: non-negative, uint8 after scaling the largest
// entry to 255. Two independent ones are ~0.7 apart (as real SIFT is).
Eigen::VectorXd RandomSiftLike(Random& random) {
  Eigen::VectorXd v(kDim);
  for (int k = 0; k < kDim; ++k) v[k] = random.Uniform();
  return v.normalized();
}

Eigen::VectorXd Perturb(const Eigen::VectorXd& v, double noise, Random& random) {
  Eigen::VectorXd out = v;
  for (int k = 0; k < kDim; ++k) out[k] = std::max(0.0, out[k] + random.Normal(0.0, noise));
  return out.normalized();
}

void SetRow(FeatureDescriptors& descriptors, Eigen::Index row, const Eigen::VectorXd& v) {
  const double scale = 255.0 / v.maxCoeff();
  for (int k = 0; k < kDim; ++k) {
    descriptors(row, k) = static_cast<uint8_t>(std::lround(std::clamp(v[k] * scale, 0.0, 255.0)));
  }
}

// Image 1 has `num1` descriptors; image 2 has noisy copies of the first
// `num_true` of them (shuffled) followed by `num_distractors` new ones.
struct SyntheticPair {
  FeatureDescriptors descriptors1;
  FeatureDescriptors descriptors2;
  std::map<point2D_t, point2D_t> truth;  // index in image 1 -> index in image 2
};

SyntheticPair MakeSyntheticPair(int num1, int num_true, int num_distractors, double noise,
                                uint64_t seed) {
  Random random(seed);
  SyntheticPair pair;
  pair.descriptors1.resize(num1, kDim);
  pair.descriptors2.resize(num_true + num_distractors, kDim);
  std::vector<Eigen::VectorXd> originals;
  for (int i = 0; i < num1; ++i) {
    originals.push_back(RandomSiftLike(random));
    SetRow(pair.descriptors1, i, originals.back());
  }
  std::vector<int> order(num_true);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), random.engine());
  for (int j = 0; j < num_true; ++j) {
    SetRow(pair.descriptors2, j, Perturb(originals[order[j]], noise, random));
    pair.truth[order[j]] = j;
  }
  for (int j = num_true; j < num_true + num_distractors; ++j) {
    SetRow(pair.descriptors2, j, RandomSiftLike(random));
  }
  return pair;
}

struct Score {
  double recall = 0.0;
  double precision = 0.0;
};

Score Evaluate(const FeatureMatches& matches, const std::map<point2D_t, point2D_t>& truth) {
  int correct = 0;
  for (const FeatureMatch& m : matches) {
    const auto it = truth.find(m.point2D_idx1);
    if (it != truth.end() && it->second == m.point2D_idx2) ++correct;
  }
  return {static_cast<double>(correct) / truth.size(),
          matches.empty() ? 0.0 : static_cast<double>(correct) / matches.size()};
}

std::vector<std::pair<point2D_t, point2D_t>> AsPairs(const FeatureMatches& matches) {
  std::vector<std::pair<point2D_t, point2D_t>> pairs;
  for (const FeatureMatch& m : matches) pairs.emplace_back(m.point2D_idx1, m.point2D_idx2);
  return pairs;
}

// Independent reference: every (i, j) that `allowed` admits, compared one
// by one, with the matcher's rules (distance, ratio test, mutual check).
template <typename Allowed>
FeatureMatches BruteForceMatches(const FloatDescriptors& d1, const FloatDescriptors& d2,
                                 const DescriptorMatchingOptions& options, Allowed allowed) {
  const Eigen::Index n1 = d1.rows();
  const Eigen::Index n2 = d2.rows();
  const float kNone = -std::numeric_limits<float>::infinity();
  Eigen::MatrixXf dots = Eigen::MatrixXf::Constant(n1, n2, kNone);
  for (Eigen::Index i = 0; i < n1; ++i) {
    for (Eigen::Index j = 0; j < n2; ++j) {
      if (allowed(i, j)) dots(i, j) = d1.row(i).dot(d2.row(j));
    }
  }
  // Best index (or -1) passing the distance and ratio tests along a row of m.
  auto best = [&](const Eigen::VectorXf& m) -> Eigen::Index {
    Eigen::Index arg = -1;
    float top = kNone;
    float second = 0.0f;
    for (Eigen::Index k = 0; k < m.size(); ++k) {
      if (m[k] > top) {
        second = std::max(second, top);
        top = m[k];
        arg = k;
      } else if (m[k] > second) {
        second = m[k];
      }
    }
    if (arg < 0) return -1;
    const double d_best = std::sqrt(std::max(0.0, 2.0 - 2.0 * top));
    const double d_second = std::sqrt(std::max(0.0, 2.0 - 2.0 * second));
    if (d_best > options.max_distance) return -1;
    if (!(d_best * d_best < options.max_ratio * options.max_ratio * d_second * d_second)) return -1;
    return arg;
  };
  FeatureMatches matches;
  for (Eigen::Index i = 0; i < n1; ++i) {
    const Eigen::Index j = best(dots.row(i).transpose());
    if (j < 0) continue;
    if (options.cross_check && best(dots.col(j)) != i) continue;
    matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(j)});
  }
  return matches;
}

FeatureMatches BruteForce(const FloatDescriptors& d1, const FloatDescriptors& d2,
                          const DescriptorMatchingOptions& options) {
  return BruteForceMatches(d1, d2, options, [](Eigen::Index, Eigen::Index) { return true; });
}

// The same restricted to the epipolar band of F.
FeatureMatches BruteForceInBand(const FloatDescriptors& d1, const FloatDescriptors& d2,
                                const std::vector<Eigen::Vector2d>& points1,
                                const std::vector<Eigen::Vector2d>& points2,
                                const Eigen::Matrix3d& F, const GuidedMatchingOptions& options) {
  return BruteForceMatches(d1, d2, options.matching, [&](Eigen::Index i, Eigen::Index j) {
    return EpipolarLineDistance(F, points1[i], points2[j]) <= options.max_epipolar_distance_px;
  });
}

TEST(NormalizeDescriptors, RowsHaveUnitNorm) {
  FeatureDescriptors descriptors(3, kDim);
  descriptors.setZero();
  descriptors(0, 0) = 3;
  descriptors(0, 1) = 4;
  descriptors.row(1).setConstant(255);
  const FloatDescriptors normalized = NormalizeDescriptors(descriptors);
  EXPECT_FLOAT_EQ(normalized(0, 0), 0.6f);
  EXPECT_FLOAT_EQ(normalized(0, 1), 0.8f);
  EXPECT_NEAR(normalized.row(1).norm(), 1.0f, 1e-6f);
  EXPECT_EQ(normalized.row(2).norm(), 0.0f);  // zeros stay zero
}

TEST(MatchDescriptors, RecallAndPrecisionOnSyntheticDescriptors) {
  // 1000 descriptors in image 1; 700 of them reappear in image 2 with noise
  // (distance ~0.2-0.3), among 500 unrelated distractors.
  const SyntheticPair pair = MakeSyntheticPair(1000, 700, 500, 0.02, 7);
  DescriptorMatchingOptions options;
  const FeatureMatches matches = MatchDescriptors(pair.descriptors1, pair.descriptors2, options);
  const Score score = Evaluate(matches, pair.truth);
  std::cout << "recall " << score.recall << " precision " << score.precision << " ("
            << matches.size() << " matches)\n";
  EXPECT_GT(score.recall, 0.97);
  EXPECT_GT(score.precision, 0.999);

  // Heavier noise: fewer pass the ratio test, those that do are still right.
  const SyntheticPair hard = MakeSyntheticPair(1000, 700, 500, 0.05, 8);
  const Score hard_score =
      Evaluate(MatchDescriptors(hard.descriptors1, hard.descriptors2, options), hard.truth);
  std::cout << "noisy: recall " << hard_score.recall << " precision " << hard_score.precision
            << "\n";
  EXPECT_LT(hard_score.recall, score.recall);
  EXPECT_GT(hard_score.recall, 0.3);
  EXPECT_GT(hard_score.precision, 0.99);

  // Without the ratio test and mutual check, distractors are matched too.
  DescriptorMatchingOptions loose;
  loose.max_ratio = 1.0;
  loose.cross_check = false;
  loose.max_distance = 2.0;
  const FeatureMatches all = MatchDescriptors(hard.descriptors1, hard.descriptors2, loose);
  // Each descriptor of image 1 with its nearest neighbour, as comparing
  // every pair finds them.
  EXPECT_EQ(AsPairs(all), AsPairs(BruteForce(NormalizeDescriptors(hard.descriptors1),
                                             NormalizeDescriptors(hard.descriptors2), loose)));
  EXPECT_GT(all.size(), 990u);
  EXPECT_LT(Evaluate(all, hard.truth).precision, 0.75);
}

// Unit vectors at given distances from e0, each in its own direction.
FloatDescriptors UnitRows(const std::vector<double>& distances_from_e0) {
  FloatDescriptors rows = FloatDescriptors::Zero(distances_from_e0.size(), kDim);
  for (size_t r = 0; r < distances_from_e0.size(); ++r) {
    const double angle = 2.0 * std::asin(distances_from_e0[r] / 2.0);
    rows(r, 0) = static_cast<float>(std::cos(angle));
    rows(r, 1 + r) = static_cast<float>(std::sin(angle));
  }
  return rows;
}

TEST(MatchDescriptors, RatioTest) {
  const FloatDescriptors query = UnitRows({0.0});
  DescriptorMatchingOptions options;
  // 0.3 / 0.4 = 0.75 < 0.8: a match with the nearer one.
  FeatureMatches matches = MatchDescriptors(query, UnitRows({0.4, 0.3}), options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].point2D_idx1, 0u);
  EXPECT_EQ(matches[0].point2D_idx2, 1u);
  // 0.3 / 0.36 = 0.83 > 0.8: ambiguous.
  EXPECT_TRUE(MatchDescriptors(query, UnitRows({0.36, 0.3}), options).empty());
  options.max_ratio = 0.9;
  EXPECT_EQ(MatchDescriptors(query, UnitRows({0.36, 0.3}), options).size(), 1u);
  // Two equally near neighbours are always ambiguous.
  options.max_ratio = 1.0;
  EXPECT_TRUE(MatchDescriptors(query, UnitRows({0.3, 0.3}), options).empty());
  // A lone candidate is compared with an orthogonal one (distance sqrt 2).
  options.max_ratio = 0.8;
  EXPECT_EQ(MatchDescriptors(query, UnitRows({0.6}), options).size(), 1u);
}

TEST(MatchDescriptors, MaxDistance) {
  const FloatDescriptors query = UnitRows({0.0});
  DescriptorMatchingOptions options;  // max_distance 0.7
  EXPECT_TRUE(MatchDescriptors(query, UnitRows({0.75}), options).empty());
  EXPECT_EQ(MatchDescriptors(query, UnitRows({0.65}), options).size(), 1u);
  options.max_distance = 0.8;
  EXPECT_EQ(MatchDescriptors(query, UnitRows({0.75}), options).size(), 1u);
}

TEST(MatchDescriptors, MutualCheck) {
  // Two descriptors of image 1 whose nearest neighbour is the same one in image 2.
  const FloatDescriptors target = UnitRows({0.0});
  DescriptorMatchingOptions options;
  options.cross_check = true;
  // From image 2's side, 0.2 / 0.3 passes the ratio test: only (0, 0) survives.
  FeatureMatches matches = MatchDescriptors(UnitRows({0.2, 0.3}), target, options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].point2D_idx1, 0u);
  EXPECT_EQ(matches[0].point2D_idx2, 0u);
  // 0.2 / 0.22 fails it from image 2's side: no match at all.
  EXPECT_TRUE(MatchDescriptors(UnitRows({0.2, 0.22}), target, options).empty());
  // Without the check both descriptors of image 1 take the same one.
  options.cross_check = false;
  EXPECT_THAT(AsPairs(MatchDescriptors(UnitRows({0.2, 0.22}), target, options)),
              ::testing::ElementsAre(std::pair<point2D_t, point2D_t>(0, 0),
                                     std::pair<point2D_t, point2D_t>(1, 0)));
}

TEST(MatchDescriptors, SameResultForAnyBlockSizeAndThreadCount) {
  const SyntheticPair pair = MakeSyntheticPair(600, 400, 300, 0.04, 3);
  const FloatDescriptors d1 = NormalizeDescriptors(pair.descriptors1);
  const FloatDescriptors d2 = NormalizeDescriptors(pair.descriptors2);
  DescriptorMatchingOptions options;
  // The reference compares every pair of descriptors one by one.
  const auto reference = AsPairs(BruteForce(d1, d2, options));
  ASSERT_GT(reference.size(), 200u);
  for (const int block_size : {1, 37, 256, 1024}) {
    for (const int threads : {1, 2, 3}) {
      options.block_size = block_size;
      options.num_threads = threads;
      EXPECT_EQ(AsPairs(MatchDescriptors(d1, d2, options)), reference)
          << "block " << block_size << " threads " << threads;
    }
  }
  EXPECT_TRUE(MatchDescriptors(d1, FloatDescriptors(0, kDim), options).empty());
}

TEST(MatchImagePairs, EqualsMatchingEachPair) {
  std::map<image_t, std::shared_ptr<const FloatDescriptors>> images;
  Random random(11);
  FeatureDescriptors first(300, kDim);
  for (image_t id = 1; id <= 4; ++id) {
    FeatureDescriptors descriptors(300, kDim);
    for (int i = 0; i < 300; ++i) SetRow(descriptors, i, RandomSiftLike(random));
    // Half of each image's descriptors are shared with image 1.
    if (id == 1) first = descriptors;
    descriptors.topRows(150) = first.topRows(150);
    images[id] = std::make_shared<const FloatDescriptors>(NormalizeDescriptors(descriptors));
  }
  const std::vector<ImagePair> pairs = {{1, 2}, {1, 3}, {2, 4}, {3, 4}};
  DescriptorMatchingOptions options;
  options.num_threads = 2;
  const std::vector<FeatureMatches> matches = MatchImagePairs(
      pairs, [&](image_t id) { return images.at(id); }, options);
  ASSERT_EQ(matches.size(), pairs.size());
  // The truth: the 150 shared descriptors are identical in every image, the
  // other 150 of each are independent (about 0.7 apart, never within the
  // ratio test of their nearest neighbour), so each pair's matches are
  // exactly (i, i) for i < 150, whatever the pair and its order in the list.
  std::vector<std::pair<point2D_t, point2D_t>> shared;
  for (point2D_t i = 0; i < 150; ++i) shared.emplace_back(i, i);
  for (size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(AsPairs(matches[k]), shared) << "pair " << k;
  }
}

// Two views of random 3D points: each point seen in both images, plus
// "repeated texture": distractors in image 2 that copy descriptors of image
// 1 but sit at unrelated positions.
struct GuidedScene {
  FeatureDescriptors raw1, raw2;  // as stored (what guided matching takes)
  FloatDescriptors d1, d2;        // normalised (brute force)
  std::vector<Eigen::Vector2d> points1, points2;
  Eigen::Matrix3d F;
  std::map<point2D_t, point2D_t> truth;
};

// The default baseline is mostly sideways (near-horizontal epipolar lines);
// a vertical one gives steep lines, which the grid walks along y.
GuidedScene MakeGuidedScene(int num_points, int num_repeated, int num_distractors, uint64_t seed,
                            const Eigen::Vector3d& translation = Eigen::Vector3d(-0.4, 0.05, 0.1)) {
  Random random(seed);
  Eigen::Matrix3d K;
  K << 458.0, 0.0, 367.0, 0.0, 457.0, 248.0, 0.0, 0.0, 1.0;
  const Rigid3d cam2_from_cam1(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())),
      translation);
  GuidedScene scene;
  scene.F = FundamentalFromRelativePose(cam2_from_cam1, K, K);
  auto project = [&](const Eigen::Vector3d& p) { return (K * p).hnormalized(); };
  auto random_pixel = [&]() {
    return Eigen::Vector2d(random.Uniform(0, 752), random.Uniform(0, 480));
  };
  const int num2 = num_points + num_repeated + num_distractors;
  FeatureDescriptors raw1(num_points, kDim), raw2(num2, kDim);
  std::vector<Eigen::VectorXd> originals;
  std::vector<int> order(num2);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), random.engine());
  scene.points2.resize(num2);
  for (int i = 0; i < num_points; ++i) {
    const Eigen::Vector3d point1 =
        (K.inverse() * random_pixel().homogeneous()) * random.Uniform(2.0, 8.0);
    scene.points1.push_back(project(point1));
    originals.push_back(RandomSiftLike(random));
    SetRow(raw1, i, originals.back());
    const int j = order[i];
    scene.points2[j] = project(cam2_from_cam1 * point1) +
                       Eigen::Vector2d(random.Normal(0, 1.0), random.Normal(0, 1.0));
    SetRow(raw2, j, Perturb(originals[i], 0.03, random));
    scene.truth[i] = j;
  }
  for (int r = 0; r < num_repeated + num_distractors; ++r) {
    const int j = order[num_points + r];
    scene.points2[j] = random_pixel();
    SetRow(raw2, j,
           r < num_repeated ? Perturb(originals[r % num_points], 0.005, random)
                            : RandomSiftLike(random));
  }
  scene.d1 = NormalizeDescriptors(raw1);
  scene.d2 = NormalizeDescriptors(raw2);
  scene.raw1 = std::move(raw1);
  scene.raw2 = std::move(raw2);
  return scene;
}

TEST(MatchDescriptorsGuided, EqualsBruteForceRestrictedToTheBand) {
  for (const Eigen::Vector3d& translation :
       {Eigen::Vector3d(-0.4, 0.05, 0.1), Eigen::Vector3d(0.03, -0.4, 0.1)}) {
    SCOPED_TRACE("baseline " + std::to_string(translation.x()) + " " +
                 std::to_string(translation.y()) + " " + std::to_string(translation.z()));
    const GuidedScene scene = MakeGuidedScene(800, 200, 400, 5, translation);
    for (const double band : {3.0, 20.0, 80.0}) {
      for (const bool cross_check : {true, false}) {
        for (const double cell : {0.0, 5.0, 200.0}) {
          GuidedMatchingOptions options;
          options.max_epipolar_distance_px = band;
          options.cell_size_px = cell;
          options.matching.cross_check = cross_check;
          options.matching.num_threads = 2;
          const FeatureMatches guided = MatchDescriptorsGuided(
              scene.raw1, scene.raw2, scene.points1, scene.points2, scene.F, options);
          const FeatureMatches reference =
              BruteForceInBand(scene.d1, scene.d2, scene.points1, scene.points2, scene.F, options);
          EXPECT_EQ(AsPairs(guided), AsPairs(reference))
              << "band " << band << " cross_check " << cross_check << " cell " << cell;
          EXPECT_GT(guided.size(), 400u);
        }
      }
    }
  }
}

TEST(MatchDescriptorsGuided, RejectsRepeatedTextureOffTheEpipolarLine) {
  // 200 of image 2's descriptors nearly copy image-1 descriptors at wrong
  // places: unguided matching takes the copies or drops both as ambiguous;
  // the epipolar band sees only the true one.
  const GuidedScene scene = MakeGuidedScene(800, 200, 400, 6);
  DescriptorMatchingOptions plain;
  const Score unguided = Evaluate(MatchDescriptors(scene.d1, scene.d2, plain), scene.truth);
  GuidedMatchingOptions options;
  options.max_epipolar_distance_px = 4.0;
  const Score guided = Evaluate(MatchDescriptorsGuided(scene.raw1, scene.raw2, scene.points1,
                                                       scene.points2, scene.F, options),
                                scene.truth);
  std::cout << "unguided recall " << unguided.recall << " precision " << unguided.precision
            << "; guided recall " << guided.recall << " precision " << guided.precision << "\n";
  EXPECT_LT(unguided.recall, 0.8);  // the 200 repeated descriptors are lost
  EXPECT_GT(guided.recall, 0.97);
  EXPECT_GT(guided.precision, 0.98);  // a few copies fall inside the 4 px band by chance
}

TEST(DescriptorMatchingOptions, ValidateNamesTheField) {
  DescriptorMatchingOptions options;
  EXPECT_TRUE(options.Check());
  options.max_ratio = 1.5;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("max_ratio"));
  options = {};
  options.max_distance = 0.0;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("max_distance"));
  options = {};
  options.block_size = 0;
  EXPECT_THAT(options.Validate(), ::testing::HasSubstr("block_size"));
  GuidedMatchingOptions guided;
  EXPECT_TRUE(guided.Check());
  guided.max_epipolar_distance_px = -1.0;
  EXPECT_THAT(guided.Validate(), ::testing::HasSubstr("max_epipolar_distance_px"));
}

}  // namespace
}  // namespace viosfm

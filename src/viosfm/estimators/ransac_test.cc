#include "viosfm/estimators/ransac.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/QR>

namespace viosfm {
namespace {

// Fits y = a x + b; the model is (a, b).
struct LineEstimator {
  using X_t = double;
  using Y_t = double;
  using M_t = Eigen::Vector2d;
  static constexpr int kMinNumSamples = 2;
  static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y) {
    // Least squares (exact for two points).
    Eigen::MatrixXd design(x.size(), 2);
    Eigen::VectorXd rhs(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      design(i, 0) = x[i];
      design(i, 1) = 1.0;
      rhs[i] = y[i];
    }
    if (x.size() == 2 && x[0] == x[1]) return {};
    return {design.colPivHouseholderQr().solve(rhs)};
  }
  static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                        std::vector<double>* squared_residuals) {
    squared_residuals->resize(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      const double residual = y[i] - (model[0] * x[i] + model[1]);
      (*squared_residuals)[i] = residual * residual;
    }
  }
};

// The same, with the per-correspondence residual: scoring stops early.
struct LineEstimatorStoppingEarly : LineEstimator {
  static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model) {
    const double residual = y - (model[0] * x + model[1]);
    return residual * residual;
  }
};

struct LineData {
  std::vector<double> x;
  std::vector<double> y;
  std::vector<char> is_inlier;
};

LineData MakeLineData(uint64_t seed, int count, double outlier_ratio, double noise) {
  Random random(seed);
  LineData data;
  for (int i = 0; i < count; ++i) {
    const double x = random.Uniform(-10, 10);
    const bool inlier = random.Uniform() >= outlier_ratio;
    data.x.push_back(x);
    data.y.push_back(inlier ? 2.0 * x + 1.0 + random.Normal(0, noise) : random.Uniform(-30, 30));
    data.is_inlier.push_back(inlier);
  }
  return data;
}

TEST(Ransac, RecoversLineWithOutliers) {
  const LineData data = MakeLineData(1, 300, 0.4, 0.01);
  RansacOptions options;
  options.max_error = 0.05;
  options.seed = 7;
  const auto report = Ransac<LineEstimator>(options).Estimate(data.x, data.y);
  ASSERT_TRUE(report.success);
  EXPECT_NEAR(report.model[0], 2.0, 1e-3);
  EXPECT_NEAR(report.model[1], 1.0, 1e-2);
  int true_inliers = 0;
  int wrong = 0;
  for (size_t i = 0; i < data.x.size(); ++i) {
    true_inliers += data.is_inlier[i];
    if (report.inlier_mask[i] && !data.is_inlier[i]) ++wrong;
  }
  // All true inliers found (noise 0.01, threshold 0.05); at most a few
  // outliers land within the band by chance.
  EXPECT_GE(static_cast<int>(report.num_inliers), true_inliers);
  EXPECT_LE(wrong, 3);
}

TEST(Ransac, SameSeedSameResult) {
  const LineData data = MakeLineData(2, 200, 0.5, 0.05);
  RansacOptions options;
  options.max_error = 0.2;
  options.seed = 42;
  const auto first = Ransac<LineEstimator>(options).Estimate(data.x, data.y);
  const auto second = Ransac<LineEstimator>(options).Estimate(data.x, data.y);
  EXPECT_EQ(first.model, second.model);  // bit-identical
  EXPECT_EQ(first.num_trials, second.num_trials);
  EXPECT_EQ(first.inlier_mask, second.inlier_mask);
  // Without local optimisation the minimal-sample models depend on the seed:
  // several seeds do not all draw the same winning sample.
  options.local_optimization = false;
  std::vector<Eigen::Vector2d> models;
  for (uint64_t seed = 0; seed < 5; ++seed) {
    options.seed = seed;
    const auto report = Ransac<LineEstimator>(options).Estimate(data.x, data.y);
    ASSERT_TRUE(report.success);
    EXPECT_NEAR(report.model[0], 2.0, 0.05);
    models.push_back(report.model);
  }
  bool all_same = true;
  for (const auto& model : models) all_same = all_same && model == models[0];
  EXPECT_FALSE(all_same);
}

// Stopping a model's scoring once its cost exceeds the best one's changes
// nothing but the time: the same model, inliers and trials, with and
// without local optimisation and with a prior model, over many data sets
// (including ones where the best model keeps changing: half outliers).
TEST(Ransac, StoppingTheScoringEarlyGivesTheSameReport) {
  int models_replaced = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const LineData data = MakeLineData(seed, 150, seed % 2 == 0 ? 0.5 : 0.2, 0.05);
    for (const bool local_optimization : {true, false}) {
      RansacOptions options;
      options.max_error = 0.2;
      options.seed = seed;
      options.min_num_trials = 20;
      options.local_optimization = local_optimization;
      const std::vector<Eigen::Vector2d> initial = {Eigen::Vector2d(1.9, 1.3)};
      for (const bool with_initial : {false, true}) {
        const auto whole = Ransac<LineEstimator>(options).Estimate(
            data.x, data.y, with_initial ? initial : std::vector<Eigen::Vector2d>{});
        const auto early = Ransac<LineEstimatorStoppingEarly>(options).Estimate(
            data.x, data.y, with_initial ? initial : std::vector<Eigen::Vector2d>{});
        ASSERT_EQ(whole.success, early.success) << seed;
        EXPECT_EQ(whole.model, early.model) << seed;
        EXPECT_EQ(whole.inlier_mask, early.inlier_mask) << seed;
        EXPECT_EQ(whole.num_inliers, early.num_inliers) << seed;
        EXPECT_EQ(whole.num_trials, early.num_trials) << seed;
        models_replaced += whole.num_trials > options.min_num_trials;
      }
    }
  }
  // Some runs needed more than the minimum of trials (the adaptive count
  // followed the best model's support), so the comparison saw it change.
  EXPECT_GT(models_replaced, 0);
}

TEST(Ransac, AdaptiveTrialCount) {
  RansacOptions options;
  options.max_error = 0.1;
  // Outlier-free data: the first sample explains everything.
  const LineData clean = MakeLineData(3, 100, 0.0, 0.0);
  EXPECT_EQ(Ransac<LineEstimator>(options).Estimate(clean.x, clean.y).num_trials, 1);
  options.min_num_trials = 25;
  EXPECT_EQ(Ransac<LineEstimator>(options).Estimate(clean.x, clean.y).num_trials, 25);
  // 70% outliers need more trials; never more than max_num_trials.
  options.min_num_trials = 0;
  const LineData noisy = MakeLineData(4, 200, 0.7, 0.01);
  const auto report = Ransac<LineEstimator>(options).Estimate(noisy.x, noisy.y);
  const int64_t needed = RansacNumTrials(report.num_inliers, 200, 2, options.confidence);
  EXPECT_GT(report.num_trials, 20);
  EXPECT_LE(report.num_trials, needed + 1);
  options.max_num_trials = 5;
  EXPECT_EQ(Ransac<LineEstimator>(options).Estimate(noisy.x, noisy.y).num_trials, 5);
}

TEST(Ransac, NumTrialsFormula) {
  // log(0.01) / log(1 - 0.5^2) = 16.008 -> 17.
  EXPECT_EQ(RansacNumTrials(50, 100, 2, 0.99), 17);
  EXPECT_EQ(RansacNumTrials(100, 100, 5, 0.999), 0);
  EXPECT_EQ(RansacNumTrials(0, 100, 5, 0.999), std::numeric_limits<int64_t>::max());
}

TEST(Ransac, TooFewDataAndOptionsValidation) {
  RansacOptions options;
  const auto report = Ransac<LineEstimator>(options).Estimate({1.0}, {2.0});
  EXPECT_FALSE(report.success);
  EXPECT_EQ(report.num_trials, 0);
  options.confidence = 1.0;
  EXPECT_NE(options.Validate().find("confidence"), std::string::npos);
  options = RansacOptions();
  options.min_num_trials = 20;
  options.max_num_trials = 10;
  EXPECT_NE(options.Validate().find("min_num_trials"), std::string::npos);
  EXPECT_TRUE(RansacOptions().Check());
}

}  // namespace
}  // namespace viosfm

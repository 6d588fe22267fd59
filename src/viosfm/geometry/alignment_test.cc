#include "viosfm/geometry/alignment.h"

#include <gtest/gtest.h>

#include <random>

namespace viosfm {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  std::vector<Eigen::Vector3d> points(count);
  for (auto& p : points) p = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
  return points;
}

std::vector<Eigen::Vector3d> Transform(const Sim3d& b_from_a,
                                       const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : points) out.push_back(b_from_a * p);
  return out;
}

const Sim3d kTruth(2.5, Eigen::Quaterniond(0.3, -0.5, 0.7, 0.2).normalized(),
                   Eigen::Vector3d(1.0, -2.0, 3.5));

void ExpectSim3Near(const Sim3d& actual, const Sim3d& expected, double tolerance) {
  EXPECT_NEAR(actual.scale, expected.scale, tolerance);
  EXPECT_NEAR(actual.rotation.angularDistance(expected.rotation), 0.0, tolerance);
  EXPECT_NEAR((actual.translation - expected.translation).norm(), 0.0, tolerance);
}

TEST(AlignPointsUmeyama, RecoversKnownSimilarity) {
  const auto src = RandomPoints(50, 1);
  const auto result = AlignPointsUmeyama(src, Transform(kTruth, src), /*with_scale=*/true);
  ASSERT_TRUE(result.has_value());
  ExpectSim3Near(*result, kTruth, 1e-9);
}

TEST(AlignPointsUmeyama, RecoversKnownRigidTransformWithoutScale) {
  const Sim3d rigid(1.0, kTruth.rotation, kTruth.translation);
  const auto src = RandomPoints(20, 2);
  const auto result = AlignPointsUmeyama(src, Transform(rigid, src), /*with_scale=*/false);
  ASSERT_TRUE(result.has_value());
  ExpectSim3Near(*result, rigid, 1e-9);
  EXPECT_EQ(result->scale, 1.0);
}

TEST(AlignPointsUmeyama, MinimalThreePoints) {
  const auto src = RandomPoints(3, 3);
  const auto result = AlignPointsUmeyama(src, Transform(kTruth, src), /*with_scale=*/true);
  ASSERT_TRUE(result.has_value());
  ExpectSim3Near(*result, kTruth, 1e-9);
}

TEST(AlignPointsUmeyama, WithoutScaleOnScaledDataKeepsScaleOne) {
  // The SE(3) fit of scaled data: the rotation is still the true one (the
  // cross-covariance only changes by a positive factor), the translation maps
  // the centroids.
  const auto src = RandomPoints(30, 4);
  const auto dst = Transform(kTruth, src);
  const auto result = AlignPointsUmeyama(src, dst, /*with_scale=*/false);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->scale, 1.0);
  EXPECT_NEAR(result->rotation.angularDistance(kTruth.rotation), 0.0, 1e-9);
  Eigen::Vector3d mean_src = Eigen::Vector3d::Zero(), mean_dst = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    mean_src += src[i] / 30.0;
    mean_dst += dst[i] / 30.0;
  }
  EXPECT_NEAR(((*result) * mean_src - mean_dst).norm(), 0.0, 1e-9);
}

TEST(AlignPointsUmeyama, NoisyPointsGiveNearTruthAndBeatTheTruthInResidual) {
  const auto src = RandomPoints(500, 5);
  auto dst = Transform(kTruth, src);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (auto& p : dst) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const auto result = AlignPointsUmeyama(src, dst, /*with_scale=*/true);
  ASSERT_TRUE(result.has_value());
  EXPECT_NEAR(result->scale, kTruth.scale, 1e-3);
  EXPECT_LT(result->rotation.angularDistance(kTruth.rotation), 1e-3);
  EXPECT_LT((result->translation - kTruth.translation).norm(), 5e-3);
  // Least squares: the estimate's residual is no larger than the truth's.
  double residual_estimate = 0.0, residual_truth = 0.0;
  for (size_t i = 0; i < src.size(); ++i) {
    residual_estimate += ((*result) * src[i] - dst[i]).squaredNorm();
    residual_truth += (kTruth * src[i] - dst[i]).squaredNorm();
  }
  EXPECT_LE(residual_estimate, residual_truth);
}

TEST(AlignPointsUmeyama, MirroredDataGivesARotationNotAReflection) {
  // dst is a reflection of src: the best proper rotation has det +1.
  const auto src = RandomPoints(40, 7);
  std::vector<Eigen::Vector3d> dst;
  for (const auto& p : src) dst.emplace_back(p.x(), p.y(), -p.z());
  const auto result = AlignPointsUmeyama(src, dst, /*with_scale=*/true);
  ASSERT_TRUE(result.has_value());
  EXPECT_NEAR(result->rotation.toRotationMatrix().determinant(), 1.0, 1e-12);
  EXPECT_GT(result->scale, 0.0);
}

TEST(AlignPointsUmeyama, DegenerateInputsGiveNullopt) {
  const auto src = RandomPoints(10, 8);
  EXPECT_FALSE(AlignPointsUmeyama({src[0], src[1]}, {src[0], src[1]}, true).has_value());
  EXPECT_FALSE(AlignPointsUmeyama(src, RandomPoints(9, 9), true).has_value());
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 10; ++i) line.push_back(Eigen::Vector3d(1, 2, 3) * i);
  EXPECT_FALSE(AlignPointsUmeyama(line, Transform(kTruth, line), true).has_value());
  EXPECT_FALSE(AlignPointsUmeyama(line, Transform(kTruth, line), false).has_value());
}

TEST(AlignPointsPositionYaw, RecoversYawAndTranslation) {
  const Sim3d truth(1.0, Eigen::Quaterniond(Eigen::AngleAxisd(2.3, Eigen::Vector3d::UnitZ())),
                    Eigen::Vector3d(-4.0, 0.5, 1.25));
  const auto src = RandomPoints(25, 10);
  const auto result = AlignPointsPositionYaw(src, Transform(truth, src));
  ASSERT_TRUE(result.has_value());
  ExpectSim3Near(*result, truth, 1e-9);
}

TEST(AlignPointsPositionYaw, NoisyDataNearTruthAndRotationStaysAboutZ) {
  const Sim3d truth(1.0, Eigen::Quaterniond(Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitZ())),
                    Eigen::Vector3d(1.0, 2.0, -0.5));
  const auto src = RandomPoints(400, 11);
  auto dst = Transform(truth, src);
  std::mt19937 rng(12);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (auto& p : dst) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const auto result = AlignPointsPositionYaw(src, dst);
  ASSERT_TRUE(result.has_value());
  EXPECT_LT(result->rotation.angularDistance(truth.rotation), 1e-3);
  EXPECT_LT((result->translation - truth.translation).norm(), 5e-3);
  const Eigen::Vector3d z_axis = result->rotation * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR((z_axis - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
}

TEST(AlignPointsPositionYaw, VerticalLineHasNoYaw) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 5; ++i) line.push_back(Eigen::Vector3d(0, 0, i));
  EXPECT_FALSE(AlignPointsPositionYaw(line, line).has_value());
  EXPECT_FALSE(AlignPointsPositionYaw({Eigen::Vector3d::Zero()}, {Eigen::Vector3d::Zero()}));
}

}  // namespace
}  // namespace viosfm

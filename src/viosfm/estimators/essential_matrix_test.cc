#include "viosfm/estimators/essential_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include "viosfm/estimators/fundamental_matrix.h"
#include "viosfm/estimators/synthetic_test_scenes.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/lie.h"

namespace viosfm {
namespace {

using testing::DirectionErrorDeg;
using testing::MakeRandomTwoView;
using testing::MinEpipolarMatrixDistance;
using testing::RotationErrorDeg;

std::vector<Eigen::Vector2d> FirstN(const std::vector<Eigen::Vector2d>& points, int n) {
  return std::vector<Eigen::Vector2d>(points.begin(), points.begin() + n);
}

TEST(EssentialMatrixFivePoint, TrueEssentialIsAmongTheSolutions) {
  Random random(1);
  constexpr int kScenes = 200;
  int recovered = 0;
  double worst = 0.0;
  for (int scene = 0; scene < kScenes; ++scene) {
    const auto view = MakeRandomTwoView(random, 5);
    const std::vector<Eigen::Matrix3d> solutions =
        EssentialMatrixFivePoint(view.points1, view.points2);
    ASSERT_LE(solutions.size(), 10u);
    // Every solution is an essential matrix satisfying the five constraints.
    for (const Eigen::Matrix3d& essential : solutions) {
      EXPECT_NEAR(essential.norm(), 1.0, 1e-12);
      for (int i = 0; i < 5; ++i) {
        EXPECT_NEAR(view.points2[i].homogeneous().dot(essential * view.points1[i].homogeneous()),
                    0.0, 1e-9);
      }
      const Eigen::Vector3d singular =
          Eigen::JacobiSVD<Eigen::Matrix3d>(essential).singularValues();
      EXPECT_NEAR(singular[0], singular[1], 1e-7);
      EXPECT_NEAR(singular[2], 0.0, 1e-7);
    }
    const double error =
        MinEpipolarMatrixDistance(solutions, EssentialFromRelativePose(view.cam2_from_cam1));
    worst = std::max(worst, error);
    if (error < 1e-8) ++recovered;
  }
  std::cout << "five-point: recovered " << recovered << " / " << kScenes << " scenes, worst error "
            << worst << "\n";
  EXPECT_EQ(recovered, kScenes);
}

TEST(EssentialMatrixFivePoint, LeastSquaresWithMorePoints) {
  Random random(2);
  for (int scene = 0; scene < 20; ++scene) {
    const auto view = MakeRandomTwoView(random, 30);
    const auto solutions = EssentialMatrixFivePoint(view.points1, view.points2);
    EXPECT_LT(MinEpipolarMatrixDistance(solutions, EssentialFromRelativePose(view.cam2_from_cam1)),
              1e-8);
  }
}

TEST(EssentialMatrixFivePoint, TooFewPoints) {
  Random random(3);
  const auto view = MakeRandomTwoView(random, 4);
  EXPECT_TRUE(EssentialMatrixFivePoint(view.points1, view.points2).empty());
}

TEST(EssentialMatrixEightPoint, RecoversTrueEssential) {
  Random random(4);
  for (int scene = 0; scene < 20; ++scene) {
    const auto view = MakeRandomTwoView(random, 12);
    const auto solutions = EssentialMatrixEightPoint(view.points1, view.points2);
    ASSERT_EQ(solutions.size(), 1u);
    EXPECT_LT(MinEpipolarMatrixDistance(solutions, EssentialFromRelativePose(view.cam2_from_cam1)),
              1e-8);
  }
  EXPECT_TRUE(EssentialMatrixEightPoint(FirstN(MakeRandomTwoView(random, 7).points1, 7),
                                        FirstN(MakeRandomTwoView(random, 7).points2, 7))
                  .empty());
}

TEST(RelativePoseFromEssential, ChoosesTheCandidateWithPointsInFront) {
  Random random(5);
  for (int scene = 0; scene < 50; ++scene) {
    const auto view = MakeRandomTwoView(random, 40);
    // Any scale and sign of E.
    const double scale = scene % 2 == 0 ? -3.0 : 0.5;
    const Eigen::Matrix3d essential = scale * EssentialFromRelativePose(view.cam2_from_cam1);
    int num_in_front = 0;
    const Rigid3d pose =
        RelativePoseFromEssential(essential, view.points1, view.points2, &num_in_front);
    EXPECT_EQ(num_in_front, 40);
    EXPECT_LT(RotationErrorDeg(pose.rotation, view.cam2_from_cam1.rotation), 1e-7);
    EXPECT_LT(DirectionErrorDeg(pose.translation, view.cam2_from_cam1.translation), 1e-7);
    EXPECT_NEAR(pose.translation.norm(), 1.0, 1e-12);
  }
}

TEST(RefineRelativePose, ConvergesFromAPerturbedPose) {
  Random random(8);
  const auto view = MakeRandomTwoView(random, 100);
  std::vector<Eigen::Vector2d> noisy1;
  std::vector<Eigen::Vector2d> noisy2;
  for (size_t i = 0; i < view.points1.size(); ++i) {
    noisy1.push_back(view.points1[i] +
                     Eigen::Vector2d(random.Normal(), random.Normal()) * 0.5 / 460);
    noisy2.push_back(view.points2[i] +
                     Eigen::Vector2d(random.Normal(), random.Normal()) * 0.5 / 460);
  }
  const Rigid3d start(
      So3Exp(testing::RandomUnitVector(random) * (2.0 * M_PI / 180)) * view.cam2_from_cam1.rotation,
      (view.cam2_from_cam1.translation + 0.05 * testing::RandomUnitVector(random)).normalized());
  const Rigid3d refined = RefineRelativePose(start, noisy1, noisy2);
  EXPECT_LT(RotationErrorDeg(refined.rotation, view.cam2_from_cam1.rotation), 0.05);
  EXPECT_LT(DirectionErrorDeg(refined.translation, view.cam2_from_cam1.translation), 0.5);
  EXPECT_NEAR(refined.translation.norm(), 1.0, 1e-12);
  // Exact correspondences: the truth is a fixed point.
  const Rigid3d fixed = RefineRelativePose(view.cam2_from_cam1, view.points1, view.points2);
  EXPECT_LT(RotationErrorDeg(fixed.rotation, view.cam2_from_cam1.rotation), 1e-9);
}

TEST(RelativePoseSampsonResiduals, JacobianMatchesCentralDifferences) {
  Random random(12);
  const auto view = MakeRandomTwoView(random, 30);
  std::vector<Eigen::Vector2d> noisy2;
  for (const Eigen::Vector2d& x : view.points2) {
    noisy2.push_back(x + Eigen::Vector2d(random.Normal(), random.Normal()) * 2.0 / 460);
  }
  // Away from the truth, so that the residuals are not all zero.
  const Rigid3d pose(
      So3Exp(testing::RandomUnitVector(random) * 0.05) * view.cam2_from_cam1.rotation,
      (view.cam2_from_cam1.translation + 0.1 * testing::RandomUnitVector(random)).normalized());
  Eigen::VectorXd residuals;
  Eigen::Matrix<double, Eigen::Dynamic, 5> jacobian;
  RelativePoseSampsonResiduals(pose, view.points1, noisy2, &residuals, &jacobian);
  Eigen::VectorXd without_jacobian;
  RelativePoseSampsonResiduals(pose, view.points1, noisy2, &without_jacobian, nullptr);
  EXPECT_EQ(residuals, without_jacobian);
  ASSERT_EQ(jacobian.rows(), 30);
  const double step = 1e-6;
  for (int k = 0; k < 5; ++k) {
    Eigen::Matrix<double, 5, 1> delta = Eigen::Matrix<double, 5, 1>::Zero();
    delta[k] = step;
    Eigen::VectorXd plus, minus;
    RelativePoseSampsonResiduals(RelativePosePlus(pose, delta), view.points1, noisy2, &plus,
                                 nullptr);
    RelativePoseSampsonResiduals(RelativePosePlus(pose, -delta), view.points1, noisy2, &minus,
                                 nullptr);
    const Eigen::VectorXd numeric = (plus - minus) / (2.0 * step);
    EXPECT_LT((jacobian.col(k) - numeric).norm(), 1e-6 * std::max(1.0, numeric.norm()))
        << "parameter " << k;
    EXPECT_GT(numeric.norm(), 1e-3) << "parameter " << k;  // a derivative worth checking
  }
}

TEST(TriangulateDepths, RecoversDepthsAndRejectsParallelRays) {
  const Rigid3d cam2_from_cam1(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-1, 0, 0));
  const Eigen::Vector3d point(0.3, -0.2, 5.0);
  double depth1 = 0.0;
  double depth2 = 0.0;
  ASSERT_TRUE(TriangulateDepths(cam2_from_cam1, point.hnormalized(),
                                (cam2_from_cam1 * point).hnormalized(), &depth1, &depth2));
  EXPECT_NEAR(depth1, 5.0, 1e-12);
  EXPECT_NEAR(depth2, 5.0, 1e-12);
  EXPECT_FALSE(TriangulateDepths(cam2_from_cam1, point.hnormalized(), point.hnormalized(), &depth1,
                                 &depth2));
}

Eigen::Matrix3d Calibration(double f, double cx, double cy) {
  Eigen::Matrix3d k;
  k << f, 0, cx, 0, f, cy, 0, 0, 1;
  return k;
}

std::vector<Eigen::Vector2d> ToPixels(const Eigen::Matrix3d& k,
                                      const std::vector<Eigen::Vector2d>& normalized) {
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& point : normalized) pixels.push_back((k * point.homogeneous()).hnormalized());
  return pixels;
}

TEST(FundamentalMatrixEightPoint, RecoversTrueFundamentalWithRankTwo) {
  Random random(6);
  const Eigen::Matrix3d k1 = Calibration(458.0, 367.0, 248.0);
  const Eigen::Matrix3d k2 = Calibration(620.0, 330.0, 250.0);
  for (int scene = 0; scene < 20; ++scene) {
    const auto view = MakeRandomTwoView(random, 20);
    const auto solutions =
        FundamentalMatrixEightPoint(ToPixels(k1, view.points1), ToPixels(k2, view.points2));
    ASSERT_EQ(solutions.size(), 1u);
    EXPECT_NEAR(solutions[0].determinant(), 0.0, 1e-12);
    EXPECT_LT(MinEpipolarMatrixDistance(solutions,
                                        FundamentalFromRelativePose(view.cam2_from_cam1, k1, k2)),
              1e-8);
  }
}

TEST(FundamentalMatrixSevenPoint, TrueFundamentalIsAmongTheSolutions) {
  Random random(7);
  const Eigen::Matrix3d k = Calibration(500.0, 320.0, 240.0);
  for (int scene = 0; scene < 50; ++scene) {
    const auto view = MakeRandomTwoView(random, 7);
    const auto solutions =
        FundamentalMatrixSevenPoint(ToPixels(k, view.points1), ToPixels(k, view.points2));
    ASSERT_GE(solutions.size(), 1u);
    ASSERT_LE(solutions.size(), 3u);
    for (const auto& fundamental : solutions) {
      EXPECT_NEAR(fundamental.determinant(), 0.0, 1e-10);
    }
    EXPECT_LT(MinEpipolarMatrixDistance(solutions,
                                        FundamentalFromRelativePose(view.cam2_from_cam1, k, k)),
              1e-7);
  }
}

TEST(SolveCubicReal, RootsOfKnownPolynomials) {
  // (a - 1)(a + 2)(a - 3) = a^3 - 2a^2 - 5a + 6.
  std::vector<double> roots = SolveCubicReal(1, -2, -5, 6);
  std::sort(roots.begin(), roots.end());
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_NEAR(roots[0], -2.0, 1e-12);
  EXPECT_NEAR(roots[1], 1.0, 1e-12);
  EXPECT_NEAR(roots[2], 3.0, 1e-12);
  // a^3 + a + 2 = (a + 1)(a^2 - a + 2): one real root.
  roots = SolveCubicReal(1, 0, 1, 2);
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_NEAR(roots[0], -1.0, 1e-12);
  // Degenerate leading coefficient: 2a^2 - 8 = 0.
  roots = SolveCubicReal(0, 2, 0, -8);
  std::sort(roots.begin(), roots.end());
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_NEAR(roots[0], -2.0, 1e-12);
  EXPECT_NEAR(roots[1], 2.0, 1e-12);
}

}  // namespace
}  // namespace viosfm

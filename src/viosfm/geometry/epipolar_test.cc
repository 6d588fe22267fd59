#include "viosfm/geometry/epipolar.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

Eigen::Matrix3d Calibration(double fx, double fy, double cx, double cy) {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

Eigen::Vector2d ToPixel(const Eigen::Matrix3d& calibration, const Eigen::Vector3d& point_in_cam) {
  return (calibration * point_in_cam).hnormalized();
}

TEST(Epipolar, ZeroErrorForExactCorrespondences) {
  Random random(21);
  const Eigen::Matrix3d k1 = Calibration(458.654, 457.296, 367.215, 248.375);
  const Eigen::Matrix3d k2 = Calibration(620.0, 615.0, 330.0, 250.0);
  int checked = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const Rigid3d cam2_from_cam1(
        So3Exp(
            Eigen::Vector3d(random.Normal(0, 0.2), random.Normal(0, 0.2), random.Normal(0, 0.2))),
        Eigen::Vector3d(random.Normal(), random.Normal(), random.Normal(0, 0.3)));
    const Eigen::Matrix3d essential = EssentialFromRelativePose(cam2_from_cam1);
    const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam2_from_cam1, k1, k2);
    // E has singular values (s, s, 0) with s = |t|.
    const Eigen::Vector3d singular = Eigen::JacobiSVD<Eigen::Matrix3d>(essential).singularValues();
    const double t_norm = cam2_from_cam1.translation.norm();
    EXPECT_NEAR(singular[0], t_norm, 1e-12);
    EXPECT_NEAR(singular[1], t_norm, 1e-12);
    EXPECT_NEAR(singular[2], 0.0, 1e-12);
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d point_in_cam1(random.Uniform(-4, 4), random.Uniform(-3, 3),
                                          random.Uniform(2, 20));
      const Eigen::Vector3d point_in_cam2 = cam2_from_cam1 * point_in_cam1;
      if (point_in_cam2.z() < 0.5) continue;
      const Eigen::Vector2d n1 = point_in_cam1.hnormalized();
      const Eigen::Vector2d n2 = point_in_cam2.hnormalized();
      EXPECT_NEAR(n2.homogeneous().dot(essential * n1.homogeneous()), 0.0, 1e-12);
      const Eigen::Vector2d x1 = ToPixel(k1, point_in_cam1);
      const Eigen::Vector2d x2 = ToPixel(k2, point_in_cam2);
      EXPECT_LT(EpipolarLineDistance(fundamental, x1, x2), 1e-9);
      EXPECT_LT(SymmetricEpipolarDistance(fundamental, x1, x2), 1e-9);
      EXPECT_LT(SampsonError(fundamental, x1, x2), 1e-18);
      // Essential matrix with identity calibrations works on normalised coordinates.
      EXPECT_LT(EpipolarLineDistance(essential, n1, n2), 1e-12);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(Epipolar, HandComputedSidewaysMotion) {
  // Camera 2 is camera 1 moved sideways: epipolar lines are the image rows
  // (v2 = v1), so the error is the row difference.
  const Eigen::Matrix3d k = Calibration(500, 500, 320, 240);
  const Rigid3d cam2_from_cam1(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-1, 0, 0));
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam2_from_cam1, k, k);
  const Eigen::Vector2d x1(100, 200);
  const Eigen::Vector2d x2(150, 203);
  EXPECT_NEAR(EpipolarLineDistance(fundamental, x1, x2), 3.0, 1e-12);
  EXPECT_NEAR(EpipolarLineDistance(fundamental, x2, x1), 3.0, 1e-12);
  EXPECT_NEAR(SymmetricEpipolarDistance(fundamental, x1, x2), 3.0, 1e-12);
  // Sampson: (3/f)^2 / (2 / f^2) = 4.5 px^2.
  EXPECT_NEAR(SampsonError(fundamental, x1, x2), 4.5, 1e-12);
  // E = [t]x for R = I.
  Eigen::Matrix3d expected_e;
  expected_e << 0, 0, 0, 0, 0, 1, 0, -1, 0;
  EXPECT_LT((EssentialFromRelativePose(cam2_from_cam1) - expected_e).norm(), 1e-15);
}

TEST(Epipolar, HandComputedRotatedCase) {
  // Camera 2 rotated 90 degrees about the y axis and translated along z.
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).matrix();
  const Rigid3d cam2_from_cam1(rotation, Eigen::Vector3d(0, 0, 1));
  Eigen::Matrix3d expected_e;
  // [t]x = [[0,-1,0],[1,0,0],[0,0,0]]; R = [[0,0,1],[0,1,0],[-1,0,0]].
  expected_e << 0, -1, 0, 0, 0, 1, 0, 0, 0;
  EXPECT_LT((EssentialFromRelativePose(cam2_from_cam1) - expected_e).norm(), 1e-15);
  // With identity calibration: x1 = (1, 2) gives the line E x1 = (-2, 1, 0),
  // i.e. -2 u + v = 0; distance of x2 = (1, 0) is |-2| / sqrt(5).
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d fundamental = FundamentalFromEssential(expected_e, identity, identity);
  EXPECT_NEAR(EpipolarLineDistance(fundamental, Eigen::Vector2d(1, 2), Eigen::Vector2d(1, 0)),
              2.0 / std::sqrt(5.0), 1e-15);
  // Other direction: F^T x2 = (0, -1, 0) for x2 = (1, 0): the line v = 0,
  // 2 away from x1 = (1, 2). Sampson = (-2)^2 / (5 + 1) = 2/3.
  EXPECT_NEAR(SymmetricEpipolarDistance(fundamental, Eigen::Vector2d(1, 2), Eigen::Vector2d(1, 0)),
              0.5 * (2.0 / std::sqrt(5.0) + 2.0), 1e-15);
  EXPECT_NEAR(SampsonError(fundamental, Eigen::Vector2d(1, 2), Eigen::Vector2d(1, 0)), 2.0 / 3.0,
              1e-15);
}

TEST(Epipolar, InvariantToScaleAndSignOfF) {
  Random random(22);
  const Eigen::Matrix3d k = Calibration(458.654, 457.296, 367.215, 248.375);
  const Rigid3d cam2_from_cam1(So3Exp(Eigen::Vector3d(0.1, -0.3, 0.05)),
                               Eigen::Vector3d(0.4, 0.1, -0.2));
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam2_from_cam1, k, k);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d x1(random.Uniform(0, 752), random.Uniform(0, 480));
    const Eigen::Vector2d x2(random.Uniform(0, 752), random.Uniform(0, 480));
    const double distance = EpipolarLineDistance(fundamental, x1, x2);
    const double symmetric = SymmetricEpipolarDistance(fundamental, x1, x2);
    const double sampson = SampsonError(fundamental, x1, x2);
    EXPECT_GT(distance, 0.0);
    for (const double factor : {-1.0, 1e-6, -3.7e4}) {
      const Eigen::Matrix3d scaled = factor * fundamental;
      EXPECT_NEAR(EpipolarLineDistance(scaled, x1, x2), distance, 1e-9 * (1 + distance));
      EXPECT_NEAR(SymmetricEpipolarDistance(scaled, x1, x2), symmetric, 1e-9 * (1 + symmetric));
      EXPECT_NEAR(SampsonError(scaled, x1, x2), sampson, 1e-9 * (1 + sampson));
    }
  }
}

TEST(Epipolar, LineUndefinedAtEpipole) {
  // Forward motion: the epipole of image 1 is the principal point (exactly
  // (0, 0) in normalised coordinates, where the epipolar line is undefined).
  const Rigid3d cam2_from_cam1(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -1));
  const Eigen::Matrix3d essential = EssentialFromRelativePose(cam2_from_cam1);
  EXPECT_TRUE(std::isinf(
      EpipolarLineDistance(essential, Eigen::Vector2d(0, 0), Eigen::Vector2d(0.1, 0.2))));
  EXPECT_TRUE(std::isinf(
      SampsonError(Eigen::Matrix3d::Zero(), Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1))));
  const Eigen::Matrix3d k = Calibration(500, 500, 320, 240);
  const Eigen::Matrix3d fundamental = FundamentalFromRelativePose(cam2_from_cam1, k, k);
  // A point elsewhere: lines through the epipole (radial lines).
  EXPECT_NEAR(
      EpipolarLineDistance(fundamental, Eigen::Vector2d(420, 240), Eigen::Vector2d(520, 243)), 3.0,
      1e-12);
}

}  // namespace
}  // namespace viosfm

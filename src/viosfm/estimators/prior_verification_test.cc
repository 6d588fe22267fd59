#include "viosfm/estimators/prior_verification.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "viosfm/estimators/synthetic_test_scenes.h"
#include "viosfm/estimators/two_view_geometry.h"
#include "viosfm/geometry/epipolar.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

using testing::RandomUnitVector;

constexpr double kDegToRad = M_PI / 180.0;

Camera TestCamera() {
  return MakeCamera(CameraModelId::kPinhole, 752, 480, {458.654, 457.296, 367.215, 248.375});
}

// Camera to IMU: a EuRoC-like rotation and lever arm.
Rigid3d TestBodyFromCam() {
  return Rigid3d(So3Exp(Eigen::Vector3d(0.02, -0.01, M_PI / 2)),
                 Eigen::Vector3d(-0.02, 0.06, 0.01));
}

// world_from_cam of a level camera at `position` (world z up) looking along
// +y rotated by `yaw` about z, pitched down by `pitch`.
Rigid3d LevelCamera(const Eigen::Vector3d& position, double yaw, double pitch = 0.0) {
  Eigen::Matrix3d world_from_level;
  // Columns: camera x (right), y (down), z (forward) in the world.
  world_from_level << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                   world_from_level *
                                   Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitX());
  return Rigid3d(rotation, position);
}

// One floor of a corridor: a textured wall 5 m ahead with some relief, and
// the floor in front of it.
std::vector<Eigen::Vector3d> FloorScene(Random& random) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 300; ++i) {
    points.emplace_back(random.Uniform(-4, 4), 5.0 + random.Uniform(-0.3, 0.3),
                        random.Uniform(0.1, 2.9));
  }
  for (int i = 0; i < 100; ++i) {
    points.emplace_back(random.Uniform(-3, 3), random.Uniform(1.5, 5.0), 0.0);
  }
  return points;
}

struct PairData {
  std::vector<Eigen::Vector2d> points1;  // normalised
  std::vector<Eigen::Vector2d> points2;
  FeatureMatches matches;
};

// Matches of points seen by camera 1 at p and by camera 2 at p + offset (the
// same-looking structure `offset` away when offset is not zero), with
// Gaussian pixel noise.
PairData MakeMatches(const Camera& camera, const std::vector<Eigen::Vector3d>& points,
                     const Rigid3d& world_from_cam1, const Rigid3d& world_from_cam2,
                     const Eigen::Vector3d& offset, double noise_px, Random& random) {
  const Rigid3d cam1_from_world = world_from_cam1.Inverse();
  const Rigid3d cam2_from_world = world_from_cam2.Inverse();
  const double focal = MeanFocalLength(camera);
  const auto visible = [&](const Eigen::Vector3d& point_in_cam) {
    const auto pixel = Project(camera, point_in_cam);
    return point_in_cam.z() > 0.1 && pixel && pixel->x() >= 0 && pixel->y() >= 0 &&
           pixel->x() < camera.width && pixel->y() < camera.height;
  };
  PairData data;
  for (const Eigen::Vector3d& point : points) {
    const Eigen::Vector3d in_cam1 = cam1_from_world * point;
    const Eigen::Vector3d in_cam2 = cam2_from_world * (point + offset);
    if (!visible(in_cam1) || !visible(in_cam2)) continue;
    const auto index = static_cast<point2D_t>(data.points1.size());
    data.points1.push_back(in_cam1.hnormalized() +
                           Eigen::Vector2d(random.Normal(0, noise_px), random.Normal(0, noise_px)) /
                               focal);
    data.points2.push_back(in_cam2.hnormalized() +
                           Eigen::Vector2d(random.Normal(0, noise_px), random.Normal(0, noise_px)) /
                               focal);
    data.matches.push_back({index, index});
  }
  return data;
}

TEST(PriorVerification, ZeroEpipolarErrorForExactCorrespondences) {
  Random random(1);
  const Camera camera1 = TestCamera();
  const Camera camera2 = MakeCamera(CameraModelId::kPinhole, 640, 480, {600, 590, 330, 245});
  const Rigid3d body_from_cam = TestBodyFromCam();
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3d world_from_body1(So3Exp(RandomUnitVector(random) * random.Uniform(0, 3)),
                                   Eigen::Vector3d(random.Normal(), random.Normal(), 1.0));
    const Rigid3d cam1_from_cam2(So3Exp(RandomUnitVector(random) * random.Uniform(0, 0.3)),
                                 RandomUnitVector(random) * random.Uniform(0.1, 2.0));
    const Rigid3d world_from_body2 =
        world_from_body1 * body_from_cam * cam1_from_cam2 * body_from_cam.Inverse();
    const testing::SyntheticTwoView view = [&] {
      // Points in front of both cameras.
      testing::SyntheticTwoView result;
      result.cam2_from_cam1 = cam1_from_cam2.Inverse();
      while (result.points1.size() < 50) {
        const Eigen::Vector3d point(random.Uniform(-2, 2), random.Uniform(-2, 2),
                                    random.Uniform(2, 8));
        const Eigen::Vector3d in_cam2 = result.cam2_from_cam1 * point;
        if (in_cam2.z() < 0.5) continue;
        result.points1.push_back(point.hnormalized());
        result.points2.push_back(in_cam2.hnormalized());
      }
      return result;
    }();
    FeatureMatches matches;
    for (point2D_t i = 0; i < view.points1.size(); ++i) matches.push_back({i, i});
    const PriorVerificationResult result =
        VerifyPairWithVioPoses(camera1, camera2, world_from_body1, world_from_body2, body_from_cam,
                               view.points1, view.points2, matches, PriorVerificationOptions());
    EXPECT_FALSE(result.rotation_only);
    ASSERT_EQ(result.errors_px.size(), matches.size());
    for (const double error : result.errors_px) EXPECT_LT(error, 1e-7);
    EXPECT_EQ(result.num_outliers, 0);
    EXPECT_EQ(result.outlier_ratio, 0.0);
    EXPECT_TRUE(result.accepted);
  }
}

TEST(PriorVerification, RelativePoseFromVioComposesExtrinsics) {
  const Rigid3d body_from_cam = TestBodyFromCam();
  const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(Eigen::Vector3d(1, 2, 1.5), 0.3);
  const Rigid3d cam2_from_cam1 =
      RelativePoseFromVio(world_from_cam1 * body_from_cam.Inverse(),
                          world_from_cam2 * body_from_cam.Inverse(), body_from_cam, body_from_cam);
  const Rigid3d expected = world_from_cam2.Inverse() * world_from_cam1;
  EXPECT_LT(cam2_from_cam1.rotation.angularDistance(expected.rotation), 1e-12);
  EXPECT_LT((cam2_from_cam1.translation - expected.translation).norm(), 1e-12);
}

// Two floors of a building with identical corridors 3.5 m apart: camera 2
// on the upper floor sees the same-looking wall and floor as camera 1 below.
// The matches agree with an epipolar geometry (that of camera 2 moved down a
// floor), so RANSAC accepts the pair; the VIO poses put the cameras 3.5 m
// apart vertically, and the epipolar error rejects it.
TEST(PriorVerification, RepeatedTextureOnDifferentFloorsIsRejected) {
  const Camera camera = TestCamera();
  const Rigid3d body_from_cam = TestBodyFromCam();
  const Eigen::Vector3d floor_offset(0, 0, 3.5);
  struct Placement {
    Eigen::Vector3d shift;  // of camera 2 within its floor, m
    double yaw_deg;
  };
  const std::vector<Placement> placements = {{{0.8, 0.6, 0.0}, 12.0},
                                             {{-1.0, 0.3, 0.0}, -8.0},
                                             {{0.3, -0.5, 0.0}, 5.0},
                                             {{0.0, 1.0, 0.0}, 0.0},
                                             {{1.5, 0.0, 0.0}, -15.0}};
  Random random(2);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  for (const Placement& placement : placements) {
    const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
    const Rigid3d world_from_cam2 = LevelCamera(
        Eigen::Vector3d(0, 0, 1.5) + placement.shift + floor_offset, placement.yaw_deg * kDegToRad);
    const PairData data =
        MakeMatches(camera, scene, world_from_cam1, world_from_cam2, floor_offset, 0.5, random);
    ASSERT_GE(data.matches.size(), 100u);

    const TwoViewGeometryResult ransac = EstimateCalibratedTwoViewGeometry(
        data.points1, data.points2, data.matches, camera, camera, TwoViewGeometryOptions());
    const PriorVerificationResult prior = VerifyPairWithVioPoses(
        camera, camera, world_from_cam1 * body_from_cam.Inverse(),
        world_from_cam2 * body_from_cam.Inverse(), body_from_cam, data.points1, data.points2,
        data.matches, PriorVerificationOptions());
    std::cout << "two floors, camera 2 shifted " << placement.shift.transpose() << " m, yaw "
              << placement.yaw_deg << " deg: " << data.matches.size()
              << " matches, RANSAC-only inliers " << ransac.num_inliers()
              << ", VIO-aided outlier ratio " << prior.outlier_ratio << "\n";
    EXPECT_EQ(ransac.config, TwoViewGeometryConfig::kCalibrated);
    EXPECT_GE(ransac.num_inliers(), 0.9 * data.matches.size());
    EXPECT_FALSE(prior.accepted);
    EXPECT_GT(prior.outlier_ratio, 0.5);
  }
}

// The same floor: correct matches, VIO poses off by 0.1 m and 1 degree.
TEST(PriorVerification, CorrectPairWithVioNoiseIsAccepted) {
  const Camera camera = TestCamera();
  const Rigid3d body_from_cam = TestBodyFromCam();
  Random random(3);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(Eigen::Vector3d(0.8, 0.6, 1.5), 12.0 * kDegToRad);
  const PairData data = MakeMatches(camera, scene, world_from_cam1, world_from_cam2,
                                    Eigen::Vector3d::Zero(), 0.5, random);
  ASSERT_GE(data.matches.size(), 100u);
  const Rigid3d world_from_body1 = world_from_cam1 * body_from_cam.Inverse();
  const Rigid3d world_from_body2 = world_from_cam2 * body_from_cam.Inverse();
  double worst_ratio = 0.0;
  double mean_ratio = 0.0;
  constexpr int kDraws = 20;
  for (int draw = 0; draw < kDraws; ++draw) {
    // Error of the relative pose: 0.1 m and 1 degree in random directions.
    const Rigid3d vio_error(So3Exp(RandomUnitVector(random) * (1.0 * kDegToRad)),
                            RandomUnitVector(random) * 0.1);
    const PriorVerificationResult result = VerifyPairWithVioPoses(
        camera, camera, world_from_body1, vio_error * world_from_body2, body_from_cam, data.points1,
        data.points2, data.matches, PriorVerificationOptions());
    EXPECT_TRUE(result.accepted) << "draw " << draw;
    worst_ratio = std::max(worst_ratio, result.outlier_ratio);
    mean_ratio += result.outlier_ratio / kDraws;
  }
  std::cout << "same floor, " << data.matches.size()
            << " matches, VIO noise 0.1 m / 1 deg: outlier ratio mean " << mean_ratio << ", worst "
            << worst_ratio << " over " << kDraws << " draws\n";
  EXPECT_LT(mean_ratio, 0.1);
  EXPECT_LT(worst_ratio, 0.4);
  // Without VIO noise only the 0.5 px pixel noise remains.
  const PriorVerificationResult exact =
      VerifyPairWithVioPoses(camera, camera, world_from_body1, world_from_body2, body_from_cam,
                             data.points1, data.points2, data.matches, PriorVerificationOptions());
  EXPECT_EQ(exact.num_outliers, 0);
  EXPECT_LT(*std::max_element(exact.errors_px.begin(), exact.errors_px.end()), 5.0);
}

// The VIO's relative pose covariance with isotropic rotation and
// translation sigmas (the residual [Log(R_E); t_E] of vio_uncertainty.h).
Eigen::Matrix<double, 6, 6> IsotropicCovariance(double rotation_sigma_rad,
                                                double translation_sigma_m) {
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  covariance.diagonal() << Eigen::Vector3d::Constant(rotation_sigma_rad * rotation_sigma_rad),
      Eigen::Vector3d::Constant(translation_sigma_m * translation_sigma_m);
  return covariance;
}

// Matches of one floor's scene between a level camera at (0, 0, 1.5) and
// one at `position2` turned by `yaw2` (0.5 px noise), and the true
// cam2_from_cam1.
struct FloorPair {
  PairData data;
  Rigid3d cam2_from_cam1;
};
FloorPair MakeFloorPair(const Camera& camera, uint64_t seed, const Eigen::Vector3d& position2,
                        double yaw2) {
  Random random(seed);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(position2, yaw2);
  return {MakeMatches(camera, scene, world_from_cam1, world_from_cam2, Eigen::Vector3d::Zero(), 0.5,
                      random),
          world_from_cam2.Inverse() * world_from_cam1};
}

// A correct pair whose VIO pose has drifted by about 4 degrees and 0.1 to
// 0.15 m (about two sigmas of its covariance), turned across the epipolar
// lines: under the VIO's pose most matches lie farther than T_EE from them
// and the fixed band rejects the pair. The correction within the drift
// finds the relative pose the matches show, under which the fixed band
// accepts it. (Two views of one wall 5 m away tell a small turn about the
// vertical from a sideways step of the baseline's direction only to a few
// tenths of a degree: the bound on the direction is looser.)
TEST(DriftCorrection, ADriftedVioPoseIsCorrectedByTheMatches) {
  const Camera camera = TestCamera();
  const FloorPair pair = MakeFloorPair(camera, 7, Eigen::Vector3d(0.8, 0.6, 1.5), 12.0 * kDegToRad);
  const PairData& data = pair.data;
  ASSERT_GE(data.matches.size(), 100u);
  const Rigid3d& truth = pair.cam2_from_cam1;
  const Eigen::Matrix<double, 6, 6> covariance = IsotropicCovariance(2.0 * kDegToRad, 0.075);
  const PriorVerificationOptions options;
  // Rotation (camera 2's axes: x right, y down, z forward), degrees, and
  // translation, m.
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> drifts = {
      {{4.0, 0.0, 0.0}, {0.15, 0.0, 0.0}},
      {{-4.5, 1.0, 0.0}, {0.0, -0.1, 0.0}},
      {{2.0, 0.0, 4.0}, {0.0, 0.0, 0.15}},
      {{-2.5, -1.0, -2.5}, {0.05, 0.1, -0.05}}};
  for (size_t draw = 0; draw < drifts.size(); ++draw) {
    const Rigid3d drift(So3Exp(drifts[draw].first * kDegToRad), drifts[draw].second);
    const Rigid3d vio = drift * truth;
    const PriorVerificationResult uncorrected =
        VerifyPairWithPrior(camera, camera, vio, data.points1, data.points2, data.matches, options);
    EXPECT_FALSE(uncorrected.accepted)
        << "draw " << draw << " outliers " << uncorrected.outlier_ratio;

    const DriftCorrection correction =
        CorrectRelativePoseWithinDrift(camera, camera, vio, covariance, data.points1, data.points2,
                                       data.matches, /*search_band_px=*/80.0,
                                       /*max_mahalanobis=*/20.0, options);
    ASSERT_TRUE(correction.corrected) << "draw " << draw;
    EXPECT_LT(correction.mahalanobis, 6.0);
    EXPECT_LT(testing::RotationErrorDeg(correction.cam2_from_cam1.rotation, truth.rotation), 0.5);
    EXPECT_LT(testing::DirectionErrorDeg(correction.cam2_from_cam1.translation, truth.translation),
              2.0);
    // The VIO's baseline length is kept.
    EXPECT_NEAR(correction.cam2_from_cam1.translation.norm(), vio.translation.norm(), 1e-9);
    const PriorVerificationResult corrected =
        VerifyPairWithPrior(camera, camera, correction.cam2_from_cam1, data.points1, data.points2,
                            data.matches, options);
    EXPECT_TRUE(corrected.accepted) << "draw " << draw;
    EXPECT_EQ(corrected.num_outliers, 0);
    // The matches' own noise is 0.5 px a keypoint.
    EXPECT_LT(*std::max_element(corrected.errors_px.begin(), corrected.errors_px.end()), 3.0);
  }
}

// Identical views a floor apart (camera 2 above camera 1, the VIO exact):
// the matches fit camera 2 at camera 1's height, a baseline turned by about
// 90 degrees from the VIO's vertical one. With the covariance of a long loop
// (1 degree, 0.1 m) that is far beyond the drift: no correction is taken,
// and the pair is rejected under the VIO's pose as before. Where camera 2
// is straight above camera 1 (5 cm off), the matches show almost no
// baseline and hardly tell its direction: the correction found is within
// the drift, and the depth check under the VIO's metric baseline, which the
// correction keeps, rejects the pair.
TEST(DriftCorrection, IdenticalFloorsAreNotADrift) {
  const Camera camera = TestCamera();
  const Eigen::Vector3d floor_offset(0, 0, 3.5);
  Random random(8);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  const Eigen::Matrix<double, 6, 6> covariance = IsotropicCovariance(1.0 * kDegToRad, 0.1);
  const PriorVerificationOptions options;
  for (const Eigen::Vector3d& shift :
       {Eigen::Vector3d(0.8, 0.6, 0.0), Eigen::Vector3d(-0.5, 0.4, 0.0),
        Eigen::Vector3d(0.05, -0.03, 0.0)}) {
    const bool straight_above = shift.norm() < 0.1;
    const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
    const Rigid3d world_from_cam2 =
        LevelCamera(Eigen::Vector3d(0, 0, 1.5) + shift + floor_offset, 3.0 * kDegToRad);
    const PairData data =
        MakeMatches(camera, scene, world_from_cam1, world_from_cam2, floor_offset, 0.5, random);
    ASSERT_GE(data.matches.size(), 100u);
    const Rigid3d vio = world_from_cam2.Inverse() * world_from_cam1;
    const DriftCorrection correction =
        CorrectRelativePoseWithinDrift(camera, camera, vio, covariance, data.points1, data.points2,
                                       data.matches, /*search_band_px=*/80.0,
                                       /*max_mahalanobis=*/20.0, options);
    std::cout << "identical floors, camera 2 shifted " << shift.transpose()
              << " m: the correction the matches ask for is " << correction.mahalanobis
              << " sigmas\n";
    if (!straight_above) {
      EXPECT_FALSE(correction.corrected);
      EXPECT_GT(correction.mahalanobis, 20.0);
      EXPECT_LT(correction.cam2_from_cam1.rotation.angularDistance(vio.rotation), 1e-12);
      EXPECT_LT((correction.cam2_from_cam1.translation - vio.translation).norm(), 1e-12);
    }
    const PriorVerificationResult result =
        VerifyPairWithPrior(camera, camera, correction.cam2_from_cam1, data.points1, data.points2,
                            data.matches, options);
    EXPECT_FALSE(result.accepted);
    if (straight_above) {
      EXPECT_NEAR(correction.cam2_from_cam1.translation.norm(), 3.5, 0.01);
      EXPECT_TRUE(result.depth_rejected);
    }
  }
}

// Nothing to correct below the minimum baseline (no direction) or with
// fewer than five matches.
TEST(DriftCorrection, NothingIsCorrectedWithoutABaselineOrMatches) {
  const Camera camera = TestCamera();
  const FloorPair pair = MakeFloorPair(camera, 9, Eigen::Vector3d(0.005, 0, 1.5), 5.0 * kDegToRad);
  const PairData& data = pair.data;
  const Rigid3d& vio = pair.cam2_from_cam1;
  const Eigen::Matrix<double, 6, 6> covariance = IsotropicCovariance(kDegToRad, 0.1);
  const DriftCorrection small_baseline =
      CorrectRelativePoseWithinDrift(camera, camera, vio, covariance, data.points1, data.points2,
                                     data.matches, 80.0, 20.0, PriorVerificationOptions());
  EXPECT_FALSE(small_baseline.corrected);
  EXPECT_TRUE(std::isnan(small_baseline.mahalanobis));
  const Rigid3d far(vio.rotation, Eigen::Vector3d(1.0, 0.0, 0.2));
  const FeatureMatches four(data.matches.begin(), data.matches.begin() + 4);
  const DriftCorrection few =
      CorrectRelativePoseWithinDrift(camera, camera, far, covariance, data.points1, data.points2,
                                     four, 80.0, 20.0, PriorVerificationOptions());
  EXPECT_FALSE(few.corrected);
  EXPECT_TRUE(std::isnan(few.mahalanobis));
}

// Pure rotation: F = K^-T [0]x R K^-1 = 0 and every epipolar line is
// undefined, so the transfer error of H = K2 R K1^-1 is used instead.
TEST(PriorVerification, PureRotationUsesInfiniteHomography) {
  const Camera camera = TestCamera();
  Random random(4);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  const Eigen::Vector3d position(0, 0, 1.5);
  const Rigid3d world_from_cam1 = LevelCamera(position, 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(position, 15.0 * kDegToRad, 5.0 * kDegToRad);
  const Rigid3d cam2_from_cam1 = world_from_cam2.Inverse() * world_from_cam1;
  ASSERT_LT(cam2_from_cam1.translation.norm(), 1e-12);
  const Eigen::Matrix3d k = CalibrationMatrix(camera);
  EXPECT_TRUE(
      std::isinf(EpipolarLineDistance(FundamentalFromRelativePose(cam2_from_cam1, k, k),
                                      Eigen::Vector2d(100, 100), Eigen::Vector2d(120, 90))));

  const PairData data = MakeMatches(camera, scene, world_from_cam1, world_from_cam2,
                                    Eigen::Vector3d::Zero(), 0.0, random);
  ASSERT_GE(data.matches.size(), 100u);
  const PriorVerificationResult exact = VerifyPairWithPrior(
      camera, camera, cam2_from_cam1, data.points1, data.points2, data.matches, {});
  EXPECT_TRUE(exact.rotation_only);
  EXPECT_TRUE(exact.accepted);
  EXPECT_FALSE(exact.depth_applied);
  EXPECT_TRUE(std::isnan(exact.depth_inconsistent_ratio));
  EXPECT_EQ(exact.outlier_ratio, 0.0);
  for (const double error : exact.errors_px) EXPECT_LT(error, 1e-8);

  // The same keypoints matched to the wrong partners (shifted by 7).
  FeatureMatches wrong = data.matches;
  for (size_t i = 0; i < wrong.size(); ++i) {
    wrong[i].point2D_idx2 = data.matches[(i + 7) % wrong.size()].point2D_idx2;
  }
  const PriorVerificationResult rejected =
      VerifyPairWithPrior(camera, camera, cam2_from_cam1, data.points1, data.points2, wrong, {});
  EXPECT_TRUE(rejected.rotation_only);
  EXPECT_FALSE(rejected.accepted);
  EXPECT_GT(rejected.outlier_ratio, 0.8);
}

// A baseline below min_baseline_m (a nearly static camera): the transfer
// error is the parallax, at most f |t| / depth.
TEST(PriorVerification, SmallBaselineFallsBackToRotation) {
  const Camera camera = TestCamera();
  Random random(5);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(Eigen::Vector3d(0.004, 0.003, 1.5), 0.1);
  const Rigid3d cam2_from_cam1 = world_from_cam2.Inverse() * world_from_cam1;
  const PairData data = MakeMatches(camera, scene, world_from_cam1, world_from_cam2,
                                    Eigen::Vector3d::Zero(), 0.0, random);
  const PriorVerificationResult result = VerifyPairWithPrior(
      camera, camera, cam2_from_cam1, data.points1, data.points2, data.matches, {});
  EXPECT_TRUE(result.rotation_only);
  EXPECT_TRUE(result.accepted);
  EXPECT_FALSE(result.depth_applied);
  EXPECT_EQ(result.num_depth_scored, 0);
  // Points at depth >= 1.5 m within ~40 degrees of the axis: parallax below
  // f |t| sqrt(1 + |x|^2) / z = 460 * 0.005 * 1.3 / 1.5 = 2 px.
  EXPECT_LT(*std::max_element(result.errors_px.begin(), result.errors_px.end()), 2.0);
  EXPECT_GT(*std::max_element(result.errors_px.begin(), result.errors_px.end()), 0.0);
}

// Wall points (with 0.1 m relief) on the plane y = `distance`, x in
// [-4, 4], z in [z_min, z_max].
std::vector<Eigen::Vector3d> WallScene(Random& random, double distance, double z_min,
                                       double z_max) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 400; ++i) {
    points.emplace_back(random.Uniform(-4, 4), distance + random.Uniform(-0.1, 0.1),
                        random.Uniform(z_min, z_max));
  }
  return points;
}

// Identical floors 3.65 m apart, camera 2 placed on its floor exactly (or
// almost) as camera 1 on its own: every match has (almost) no image motion,
// so it lies on its epipolar line of the vertical VIO baseline and the
// paper's EE test accepts the pair. No point nearer than 20 m can show so
// little parallax over a 3.65 m baseline (at least 460 * 3.65 / 20 = 84 px),
// so the depth check rejects it.
TEST(PriorVerification, IdenticalViewsOnStackedFloorsFailDepthCheck) {
  const Camera camera = TestCamera();
  const Rigid3d body_from_cam = TestBodyFromCam();
  const Eigen::Vector3d floor_offset(0, 0, 3.65);
  struct Placement {
    Eigen::Vector3d shift;  // of camera 2 within its floor, m
    double yaw_deg;
  };
  const std::vector<Placement> placements = {
      {{0.0, 0.0, 0.0}, 0.0}, {{0.03, -0.02, 0.0}, 0.5}, {{-0.05, 0.04, 0.0}, -1.0}};
  Random random(6);
  const std::vector<Eigen::Vector3d> scene = FloorScene(random);
  for (const Placement& placement : placements) {
    const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
    const Rigid3d world_from_cam2 = LevelCamera(
        Eigen::Vector3d(0, 0, 1.5) + placement.shift + floor_offset, placement.yaw_deg * kDegToRad);
    const PairData data =
        MakeMatches(camera, scene, world_from_cam1, world_from_cam2, floor_offset, 0.5, random);
    ASSERT_GE(data.matches.size(), 100u);
    const Rigid3d world_from_body1 = world_from_cam1 * body_from_cam.Inverse();
    const Rigid3d world_from_body2 = world_from_cam2 * body_from_cam.Inverse();

    PriorVerificationOptions paper;
    paper.check_depth = false;
    const PriorVerificationResult epipolar_only =
        VerifyPairWithVioPoses(camera, camera, world_from_body1, world_from_body2, body_from_cam,
                               data.points1, data.points2, data.matches, paper);
    EXPECT_TRUE(epipolar_only.accepted);
    EXPECT_LT(epipolar_only.outlier_ratio, 0.1);
    EXPECT_FALSE(epipolar_only.depth_applied);

    const PriorVerificationResult result = VerifyPairWithVioPoses(
        camera, camera, world_from_body1, world_from_body2, body_from_cam, data.points1,
        data.points2, data.matches, PriorVerificationOptions());
    EXPECT_TRUE(result.accepted_epipolar);
    EXPECT_EQ(result.outlier_ratio, epipolar_only.outlier_ratio);
    EXPECT_TRUE(result.depth_applied);
    EXPECT_GE(result.num_depth_scored, static_cast<int>(0.9 * data.matches.size()));
    EXPECT_GT(result.depth_inconsistent_ratio, 0.95);
    EXPECT_TRUE(result.depth_rejected);
    EXPECT_FALSE(result.accepted);
  }
}

// The same 3.65 m baselines (vertical, and horizontal) between two views of
// one wall 3 m away: the parallax is several hundred pixels, far above the
// bound, and the pair passes, also with VIO errors of 0.1 m and 1 degree.
TEST(PriorVerification, LargeBaselineOnNearSceneKeepsPair) {
  const Camera camera = TestCamera();
  const Rigid3d body_from_cam = TestBodyFromCam();
  Random random(7);
  struct Views {
    Rigid3d world_from_cam1;
    Rigid3d world_from_cam2;
  };
  const std::vector<Views> views = {
      // Vertical: camera 1 pitched up, camera 2 3.65 m higher pitched down.
      {LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0, -30.0 * kDegToRad),
       LevelCamera(Eigen::Vector3d(0, 0, 5.15), 0.0, 30.0 * kDegToRad)},
      // Horizontal, toed in.
      {LevelCamera(Eigen::Vector3d(0, 0, 1.5), -25.0 * kDegToRad),
       LevelCamera(Eigen::Vector3d(3.65, 0, 1.5), 25.0 * kDegToRad)}};
  const std::vector<Eigen::Vector3d> scene = WallScene(random, 3.0, 0.0, 7.0);
  for (const Views& view : views) {
    const PairData data = MakeMatches(camera, scene, view.world_from_cam1, view.world_from_cam2,
                                      Eigen::Vector3d::Zero(), 0.5, random);
    ASSERT_GE(data.matches.size(), 50u);
    const Rigid3d world_from_body1 = view.world_from_cam1 * body_from_cam.Inverse();
    const Rigid3d world_from_body2 = view.world_from_cam2 * body_from_cam.Inverse();
    for (int draw = 0; draw < 10; ++draw) {
      const Rigid3d vio_error = draw == 0
                                    ? Rigid3d()
                                    : Rigid3d(So3Exp(RandomUnitVector(random) * (1.0 * kDegToRad)),
                                              RandomUnitVector(random) * 0.1);
      const PriorVerificationResult result = VerifyPairWithVioPoses(
          camera, camera, world_from_body1, vio_error * world_from_body2, body_from_cam,
          data.points1, data.points2, data.matches, PriorVerificationOptions());
      EXPECT_TRUE(result.accepted) << "draw " << draw;
      EXPECT_TRUE(result.depth_applied);
      EXPECT_EQ(result.num_depth_inconsistent, 0) << "draw " << draw;
    }
  }
}

// A 0.5 m baseline on a scene 40 to 60 m away (outdoors, or a far wall): a
// point at 20 m would move only 460 * 0.5 / 20 = 11.5 px, below the 40 px
// needed to score a match, so the check does not apply and the far points
// (which are beyond max_scene_depth_m) do not reject the pair.
TEST(PriorVerification, SmallBaselineFarSceneNotScored) {
  const Camera camera = TestCamera();
  Random random(8);
  const std::vector<Eigen::Vector3d> scene = WallScene(random, 50.0, -20.0, 20.0);
  const Rigid3d world_from_cam1 = LevelCamera(Eigen::Vector3d(0, 0, 1.5), 0.0);
  const Rigid3d world_from_cam2 = LevelCamera(Eigen::Vector3d(0.5, 0.0, 1.5), 0.05);
  const PairData data = MakeMatches(camera, scene, world_from_cam1, world_from_cam2,
                                    Eigen::Vector3d::Zero(), 0.5, random);
  ASSERT_GE(data.matches.size(), 100u);
  const PriorVerificationResult result =
      VerifyPairWithPrior(camera, camera, world_from_cam2.Inverse() * world_from_cam1, data.points1,
                          data.points2, data.matches, PriorVerificationOptions());
  EXPECT_FALSE(result.rotation_only);
  EXPECT_TRUE(result.accepted);
  EXPECT_EQ(result.num_depth_scored, 0);
  EXPECT_FALSE(result.depth_applied);
  EXPECT_FALSE(result.depth_rejected);
}

TEST(PriorVerification, NoMatchesIsRejected) {
  const Camera camera = TestCamera();
  const PriorVerificationResult result = VerifyPairWithPrior(
      camera, camera, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)), {}, {}, {},
      PriorVerificationOptions());
  EXPECT_FALSE(result.accepted);
  EXPECT_EQ(result.num_matches, 0);
  EXPECT_EQ(result.outlier_ratio, 1.0);
}

TEST(PriorVerificationOptions, PaperDefaultsAndValidation) {
  const PriorVerificationOptions defaults;
  EXPECT_EQ(defaults.max_epipolar_error_px, 20.0);
  EXPECT_EQ(defaults.max_outlier_ratio, 0.5);
  EXPECT_TRUE(defaults.Check());
  PriorVerificationOptions options;
  options.max_outlier_ratio = 1.5;
  EXPECT_NE(options.Validate().find("max_outlier_ratio"), std::string::npos);
  options = PriorVerificationOptions();
  options.max_epipolar_error_px = -1.0;
  EXPECT_NE(options.Validate().find("max_epipolar_error_px"), std::string::npos);
  EXPECT_TRUE(defaults.check_depth);
  options = PriorVerificationOptions();
  options.max_scene_depth_m = 0.0;
  EXPECT_NE(options.Validate().find("max_scene_depth_m"), std::string::npos);
  options = PriorVerificationOptions();
  options.min_depth_parallax_px = 0.0;
  EXPECT_NE(options.Validate().find("min_depth_parallax_px"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

// The drift's distance of a relative pose: zero at the VIO's own pose
// (whatever its translation's length), one per standard deviation of the
// covariance along a rotation axis or across the direction, and half a turn
// of direction for a reversed translation.
TEST(RelativePoseDrift, SigmasOfRotationAndDirection) {
  const Rigid3d vio(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(0.0, 0.0, 2.0));
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  const double rotation_sigma = 0.01;     // rad
  const double translation_sigma = 0.05;  // m: 0.025 rad of direction at 2 m
  covariance.diagonal() << Eigen::Vector3d::Constant(rotation_sigma * rotation_sigma),
      Eigen::Vector3d::Constant(translation_sigma * translation_sigma);
  const RelativePoseDrift drift(vio, covariance);
  EXPECT_NEAR(drift.Mahalanobis(vio), 0.0, 1e-9);
  EXPECT_NEAR(drift.Mahalanobis(Rigid3d(vio.rotation, 7.0 * vio.translation)), 0.0, 1e-9);

  const Eigen::Quaterniond turn(Eigen::AngleAxisd(3.0 * rotation_sigma, Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(drift.Mahalanobis(Rigid3d(turn * vio.rotation, vio.translation)), 3.0, 1e-6);

  const double angle = 4.0 * translation_sigma / 2.0;  // 4 sigmas across the 2 m baseline
  const Eigen::Vector3d tilted(std::sin(angle), 0.0, std::cos(angle));
  EXPECT_NEAR(drift.Mahalanobis(Rigid3d(vio.rotation, tilted)), 4.0, 1e-6);

  EXPECT_NEAR(drift.Mahalanobis(Rigid3d(vio.rotation, -vio.translation)),
              M_PI / (translation_sigma / 2.0), 1e-6);
}

}  // namespace
}  // namespace viosfm

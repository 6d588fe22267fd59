#include "viosfm/scene/vio_uncertainty.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

namespace viosfm {
namespace {

VioSample Frame(double t_s, const Eigen::Vector3d& center, double yaw_rad, double distance_m,
                double rotation_rad = 0.0, int segment = 0) {
  VioSample frame;
  frame.timestamp_ns = static_cast<timestamp_ns_t>(std::llround(t_s * 1e9));
  frame.world_from_cam =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())), center);
  frame.odometer = {segment, distance_m, rotation_rad};
  return frame;
}

TEST(VioUncertainty, CovarianceGrowsWithTimeDistanceAndRotation) {
  const VioUncertaintyModel model;
  const VioSample start = Frame(0.0, Eigen::Vector3d::Zero(), 0.0, 0.0);
  double previous_rotation = 0.0;
  double previous_translation = 0.0;
  for (const double seconds : {0.05, 1.0, 7.0, 60.0}) {
    // Walking at 0.4 m/s along x, turning 0.2 rad/s.
    const VioSample later =
        Frame(seconds, Eigen::Vector3d(0.4 * seconds, 0, 0), 0.0, 0.4 * seconds, 0.2 * seconds);
    const Eigen::Matrix<double, 6, 6> cov = RelativePoseCovariance(model, start, later);
    EXPECT_LT((cov - cov.transpose()).norm(), 1e-15);
    using Solver = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>;
    EXPECT_GT(Solver(cov).eigenvalues().minCoeff(), 0.0);
    const RelativePoseSigmas sigmas = LargestSigmas(cov);
    EXPECT_GT(sigmas.rotation_rad, previous_rotation);
    EXPECT_GT(sigmas.translation_m, previous_translation);
    previous_rotation = sigmas.rotation_rad;
    previous_translation = sigmas.translation_m;
  }
  // 0.05 s apart: the frame noise of both frames (white and correlated).
  const Eigen::Matrix<double, 6, 6> close =
      RelativePoseCovariance(model, start, Frame(0.05, Eigen::Vector3d(0.02, 0, 0), 0.0, 0.02));
  const double rho = std::exp(-0.05 / model.noise_correlation_s);
  const double noise =
      2.0 * (model.position_noise_m * model.position_noise_m +
             model.correlated_position_noise_m * model.correlated_position_noise_m * (1.0 - rho));
  // The camera looks along world x (identity rotation): world z is camera z.
  // Frame 1's rotation noise turns the 2 cm displacement too.
  const double lever = (model.rotation_noise_rad * model.rotation_noise_rad +
                        model.correlated_rotation_noise_rad * model.correlated_rotation_noise_rad) *
                       0.02 * 0.02;
  EXPECT_NEAR(close(5, 5),
              noise + lever + model.position_per_sqrt_s * model.position_per_sqrt_s * 0.05 +
                  model.position_per_sqrt_m * model.position_per_sqrt_m * 0.02,
              1e-15);
  // Yaw drift after 60 s and 24 m and 12 rad, about world z = camera z here.
  const Eigen::Matrix<double, 6, 6> far =
      RelativePoseCovariance(model, start, Frame(60.0, Eigen::Vector3d(24, 0, 0), 0.0, 24.0, 12.0));
  const double yaw_var = model.yaw_per_sqrt_s * model.yaw_per_sqrt_s * 60 +
                         model.yaw_per_sqrt_m * model.yaw_per_sqrt_m * 24 +
                         model.yaw_per_sqrt_rad * model.yaw_per_sqrt_rad * 12;
  const double rotation_noise =
      2.0 * (model.rotation_noise_rad * model.rotation_noise_rad +
             model.correlated_rotation_noise_rad * model.correlated_rotation_noise_rad *
                 (1.0 - std::exp(-60.0)));
  EXPECT_NEAR(far(2, 2), yaw_var + rotation_noise, 1e-12);
  // The yaw error moves the 24 m displacement sideways (world y): its
  // lateral variance includes yaw_var * 24^2 / 3, correlated with the yaw.
  EXPECT_GT(far(4, 4), yaw_var * 24 * 24 / 3);
  // (plus frame 1's rotation noise through the lever arm: 24 (var - covar)).
  EXPECT_NEAR(far(4, 2), yaw_var * 24 / 2 + 24 * rotation_noise / 2, 1e-12);
  // And the scale error along it.
  EXPECT_GT(far(3, 3), model.scale_sigma * model.scale_sigma * 24 * 24);
}

TEST(VioUncertainty, CovarianceIsInTheSecondCamerasFrame) {
  const VioUncertaintyModel model;
  const VioSample a = Frame(0.0, Eigen::Vector3d::Zero(), 0.0, 0.0);
  VioSample b = Frame(10.0, Eigen::Vector3d(4, 0, 0), 0.0, 4.0);
  const Eigen::Matrix<double, 6, 6> unrotated = RelativePoseCovariance(model, a, b);
  // Camera 2 turned by 90 degrees about x: its y axis is world z.
  b.world_from_cam.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());
  const Eigen::Matrix<double, 6, 6> rotated = RelativePoseCovariance(model, a, b);
  EXPECT_NEAR(rotated(1, 1), unrotated(2, 2), 1e-12);  // yaw
  EXPECT_NEAR(rotated(4, 4), unrotated(5, 5), 1e-12);  // vertical translation
  EXPECT_NEAR(rotated(0, 0), unrotated(0, 0), 1e-12);
}

TEST(VioUncertainty, SqrtInformationWhitens) {
  const VioUncertaintyModel model;
  const Eigen::Matrix<double, 6, 6> cov =
      RelativePoseCovariance(model, Frame(0, Eigen::Vector3d::Zero(), 0, 0),
                             Frame(3, Eigen::Vector3d(1, 1, 0), 0.5, 1.5, 0.6));
  const Eigen::Matrix<double, 6, 6> s = SqrtInformationFromCovariance(cov);
  EXPECT_LT((s * cov * s.transpose() - Eigen::Matrix<double, 6, 6>::Identity()).norm(), 1e-8);
}

TEST(VioUncertainty, ScaledAndValidate) {
  const VioUncertaintyModel model;
  EXPECT_TRUE(model.Check());
  const VioUncertaintyModel doubled = model.Scaled(2.0);
  EXPECT_DOUBLE_EQ(doubled.yaw_per_sqrt_m, 2 * model.yaw_per_sqrt_m);
  EXPECT_DOUBLE_EQ(doubled.noise_correlation_s, model.noise_correlation_s);
  const VioSample a = Frame(0, Eigen::Vector3d::Zero(), 0, 0);
  const VioSample b = Frame(2, Eigen::Vector3d(1, 0, 0), 0, 1);
  EXPECT_LT(
      (RelativePoseCovariance(doubled, a, b) - 4 * RelativePoseCovariance(model, a, b)).norm(),
      1e-15);
  VioUncertaintyModel bad = model;
  bad.rotation_noise_rad = 0;
  EXPECT_NE(bad.Validate().find("rotation_noise_rad"), std::string::npos);
  bad = model;
  bad.yaw_per_sqrt_m = -1;
  EXPECT_NE(bad.Validate().find("yaw_per_sqrt_m"), std::string::npos);
  EXPECT_TRUE(VioUncertaintyModel::Exact().Check());
  EXPECT_EQ(model.ToKeyValues().size(), 13u);
  bad = model;
  bad.relative_scale_sigma = -0.01;
  EXPECT_NE(bad.Validate().find("relative_scale_sigma"), std::string::npos);
}

// The model within one segment (the relative-pose priors') differs from the
// whole one by the scale alone: along the displacement, the variance
// relative_scale_sigma^2 |d|^2 instead of scale_sigma^2 |d|^2; across it and
// in the rotation, nothing.
TEST(VioUncertainty, WithinSegmentKeepsOnlyTheScalesVariation) {
  const VioUncertaintyModel model;
  const VioUncertaintyModel within = model.WithinSegment();
  EXPECT_DOUBLE_EQ(within.scale_sigma, model.relative_scale_sigma);
  EXPECT_DOUBLE_EQ(within.relative_scale_sigma, model.relative_scale_sigma);
  EXPECT_DOUBLE_EQ(within.yaw_per_sqrt_m, model.yaw_per_sqrt_m);
  // 5 m along world x with world_from_cam the identity: the displacement is
  // the camera's x, translation row 3.
  const VioSample a = Frame(0, Eigen::Vector3d::Zero(), 0, 0);
  const VioSample b = Frame(7, Eigen::Vector3d(5, 0, 0), 0, 5);
  const Eigen::Matrix<double, 6, 6> whole = RelativePoseCovariance(model, a, b);
  const Eigen::Matrix<double, 6, 6> part = RelativePoseCovariance(within, a, b);
  Eigen::Matrix<double, 6, 6> expected = whole;
  expected(3, 3) -= (model.scale_sigma * model.scale_sigma -
                     model.relative_scale_sigma * model.relative_scale_sigma) *
                    25.0;
  EXPECT_LT((part - expected).norm(), 1e-15);
  EXPECT_LT(part(3, 3), 0.5 * whole(3, 3));
}

TEST(VioUncertainty, SegmentsAndOdometers) {
  Trajectory trajectory;
  const timestamp_ns_t s = 1'000'000'000;
  for (const timestamp_ns_t t : {0 * s, s / 10, 2 * s / 10, 2 * s, 2 * s + s / 10}) {
    trajectory.poses.push_back(
        {t, Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * t / s, Eigen::Vector3d::UnitZ())),
                    Eigen::Vector3d(static_cast<double>(t) / s, 0, 0))});
  }
  EXPECT_EQ(SegmentsFromTimeGaps(trajectory, s / 2), (std::vector<int>{0, 0, 0, 1, 1}));
  EXPECT_EQ(SegmentsFromTimeGaps(trajectory, 0), (std::vector<int>{0, 0, 0, 0, 0}));
  const std::vector<VioOdometer> odometers =
      ComputeVioOdometers(trajectory, SegmentsFromTimeGaps(trajectory, s / 2));
  EXPECT_NEAR(odometers[2].distance_m, 0.2, 1e-12);
  EXPECT_NEAR(odometers[2].rotation_rad, 0.02, 1e-12);
  EXPECT_EQ(odometers[3].segment, 1);
  EXPECT_EQ(odometers[3].distance_m, 0.0);
  EXPECT_NEAR(odometers[4].distance_m, 0.1, 1e-12);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sfm/imu_scale.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// A hand-held-like motion with closed-form derivatives: position a sum of
// sinusoids (about 0.5 m/s, 0.5 m/s^2, times `amplitude`), rotation
// yaw-pitch-roll sinusoids.
double amplitude = 1.0;
Eigen::Vector3d Position(double t) {
  return amplitude * Eigen::Vector3d{1.5 * std::sin(0.6 * t) + 0.3 * std::sin(1.7 * t),
                                     1.2 * std::cos(0.45 * t) + 0.2 * std::sin(2.3 * t),
                                     1.2 + 0.2 * std::sin(0.9 * t)};
}
Eigen::Vector3d Acceleration(double t) {
  return amplitude *
         Eigen::Vector3d{-1.5 * 0.36 * std::sin(0.6 * t) - 0.3 * 2.89 * std::sin(1.7 * t),
                         -1.2 * 0.2025 * std::cos(0.45 * t) - 0.2 * 5.29 * std::sin(2.3 * t),
                         -0.2 * 0.81 * std::sin(0.9 * t)};
}
Eigen::Matrix3d Rotation(double t) {
  return (Eigen::AngleAxisd(0.8 * std::sin(0.3 * t) + 0.05 * t, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.1 * std::sin(0.7 * t), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(0.05 * std::sin(1.1 * t), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

struct Data {
  std::vector<ImuSample> imu;
  ImuNoise noise;
};

// 200 Hz IMU over [0, duration] with EuRoC-like noise and constant biases.
Data MakeImu(double duration_s, uint64_t seed) {
  Data data;
  Random random(seed);
  const Eigen::Vector3d gyro_bias(0.002, -0.001, 0.003);
  const Eigen::Vector3d accel_bias(0.05, -0.03, 0.04);
  const double dt = 1.0 / data.noise.rate_hz;
  const double h = 1e-5;
  for (int k = 0; k * dt <= duration_s; ++k) {
    const double t = k * dt;
    const Eigen::Matrix3d rotation = Rotation(t);
    const Eigen::AngleAxisd turn(Rotation(t - h).transpose() * Rotation(t + h));
    const Eigen::Vector3d omega = turn.angle() * turn.axis() / (2 * h);
    const Eigen::Vector3d force =
        rotation.transpose() * (Acceleration(t) - Eigen::Vector3d(0, 0, -kStandardGravity));
    ImuSample sample;
    sample.timestamp_ns = static_cast<timestamp_ns_t>(std::llround(t * 1e9));
    for (int a = 0; a < 3; ++a) {
      sample.gyro[a] = omega[a] + gyro_bias[a] + random.Normal(0, data.noise.GyroSampleStddev());
      sample.accel[a] = force[a] + accel_bias[a] + random.Normal(0, data.noise.AccelSampleStddev());
    }
    data.imu.push_back(sample);
  }
  return data;
}

// Body poses at the stamps, positions divided by `true_scale` (the
// reconstruction's units), with `position_noise_m` (1 mm) / 0.5 mrad noise.
Trajectory Reconstruction(const std::vector<double>& stamps_s, double true_scale, uint64_t seed,
                          double position_noise_m = 0.001) {
  Random random(seed);
  Trajectory trajectory;
  for (const double t : stamps_s) {
    const Eigen::Vector3d noise_angle(random.Normal(0, 5e-4), random.Normal(0, 5e-4),
                                      random.Normal(0, 5e-4));
    const Eigen::Matrix3d rotation =
        Rotation(t) *
        Eigen::AngleAxisd(noise_angle.norm(), noise_angle.normalized()).toRotationMatrix();
    const Eigen::Vector3d position =
        Position(t) / true_scale + Eigen::Vector3d(random.Normal(0, position_noise_m),
                                                   random.Normal(0, position_noise_m),
                                                   random.Normal(0, position_noise_m));
    trajectory.poses.push_back({static_cast<timestamp_ns_t>(std::llround(t * 1e9)),
                                Rigid3d(Eigen::Quaterniond(rotation), position)});
  }
  return trajectory;
}

// Frames at 10 Hz from 1 to 61 s.
std::vector<double> TenHzStamps() {
  std::vector<double> stamps;
  for (int k = 0; k <= 600; ++k) stamps.push_back(1.0 + 0.1 * k);
  return stamps;
}

// The fit over consecutive frames alone (no spacing check).
ImuScaleResult EstimateFromConsecutiveFrames(const Trajectory& reconstruction, const Data& data) {
  ImuScaleOptions unchecked;
  unchecked.spacing_check_interval_s = 0.0;
  return EstimateImuScale(reconstruction, data.imu, data.noise, unchecked);
}

TEST(ImuScale, RecoversTheScaleOfA10HzTrajectory) {
  const Data data = MakeImu(62.0, 1);
  const std::vector<double> stamps = TenHzStamps();
  const ImuScaleResult result =
      EstimateImuScale(Reconstruction(stamps, 1.02, 2), data.imu, data.noise);
  ASSERT_TRUE(result.usable) << result.message;
  EXPECT_NEAR(result.scale, 1.02, 0.002) << result.message;
  EXPECT_LT(result.scale_sigma, 0.002);  // (measured 0.1 %)
  EXPECT_LT((result.gravity_in_world - Eigen::Vector3d(0, 0, -kStandardGravity)).norm(), 0.02);
  // The frames 1 s apart agree with the consecutive ones, and their scale,
  // precise enough (0.07 %), is the estimate.
  EXPECT_FALSE(result.spacing_disagrees);
  EXPECT_TRUE(result.spaced_used);
  EXPECT_EQ(result.num_pairs, 60);
  EXPECT_EQ(result.scale, result.spaced_scale);
  EXPECT_NE(result.message.find("frames at least 1.00 s apart, which the frames' jitter does not "
                                "shrink; consecutive frames give 1.0"),
            std::string::npos)
      << result.message;
}

// Jitter too small for the check to notice still shrinks the consecutive
// frames' scale by more than the spaced frames' error: 1.5 mm at 10 Hz
// takes 0.35 % off it (1.3 sigma from the spaced frames' scale), which
// would spend most of a 0.5 % budget; the spaced frames' scale is 0.07 %
// from the truth.
TEST(ImuScale, SpacedFramesGiveTheScaleWhenPreciseEnough) {
  const Data data = MakeImu(62.0, 1);
  const std::vector<double> stamps = TenHzStamps();
  const Trajectory reconstruction = Reconstruction(stamps, 1.02, 2, 0.0015);
  const ImuScaleResult consecutive = EstimateFromConsecutiveFrames(reconstruction, data);
  const ImuScaleResult result = EstimateImuScale(reconstruction, data.imu, data.noise);
  EXPECT_LT(consecutive.scale / 1.02, 0.9975) << consecutive.message;
  EXPECT_FALSE(result.spacing_disagrees) << result.message;
  ASSERT_TRUE(result.usable) << result.message;
  EXPECT_TRUE(result.spaced_used);
  EXPECT_NEAR(result.scale / 1.02, 1.0, 0.0015) << result.message;
  EXPECT_NEAR(result.scale, 1.02, 3.0 * result.scale_sigma * 1.02) << result.message;
}

// Four frames of 1.5 s of motion: 18 equations for 18 unknowns (scale,
// gravity, biases, velocities). The least squares fits them exactly, and
// its residual, nearly zero, would claim a scale precise to 0.01 % where
// the truth is far off; the fit refuses instead. The spaced frames' fit of
// a short walk (4 frames 1 s apart) is refused the same way, and the
// consecutive frames' stands.
TEST(ImuScale, TooFewEquationsForTheUnknownsIsNotAScale) {
  const Data data = MakeImu(6.0, 1);
  const ImuScaleResult four =
      EstimateImuScale(Reconstruction({1.0, 1.5, 2.0, 2.5}, 1.02, 2), data.imu, data.noise);
  EXPECT_FALSE(four.usable);
  EXPECT_NE(four.message.find("18 equations for 18 unknowns from 3 frame pairs"), std::string::npos)
      << four.message;
  std::vector<double> stamps;
  for (int k = 0; k <= 35; ++k) stamps.push_back(1.0 + 0.1 * k);
  const ImuScaleResult short_walk =
      EstimateImuScale(Reconstruction(stamps, 1.02, 2), data.imu, data.noise);
  EXPECT_FALSE(short_walk.spaced_used) << short_walk.message;
  EXPECT_EQ(short_walk.num_pairs, 35);
  EXPECT_NEAR(short_walk.scale, 1.02, 3.0 * short_walk.scale_sigma * 1.02) << short_walk.message;
}

TEST(ImuScale, RecoversTheScaleOfKeyframesWithIrregularGaps) {
  const Data data = MakeImu(150.0, 3);
  Random random(4);
  std::vector<double> stamps;
  for (double t = 1.0; t < 149.0; t += std::exp(random.Uniform(std::log(0.05), std::log(7.0)))) {
    stamps.push_back(t);
  }
  const ImuScaleResult result =
      EstimateImuScale(Reconstruction(stamps, 0.985, 5), data.imu, data.noise);
  ASSERT_TRUE(result.usable) << result.message;  // (sigma 0.35 %)
  EXPECT_NEAR(result.scale, 0.985, 0.003) << result.message;
}

// The real recording's case: a gentle walk (accelerations of 0.03-0.3
// m/s^2) whose frames, 0.1 s apart, jitter by 2 mm. Over consecutive
// frames the jitter is as large as the displacement the acceleration adds,
// and the fit shrinks the scale (0.81); frames 1 s apart are not shrunk
// (1.004 +- 0.006).
TEST(ImuScale, JitterOverShortPairsDoesNotShrinkTheScale) {
  amplitude = 0.15;
  const Data data = MakeImu(62.0, 8);
  const std::vector<double> stamps = TenHzStamps();
  const Trajectory reconstruction = Reconstruction(stamps, 1.0, 9, 0.002);
  const ImuScaleResult shrunk = EstimateFromConsecutiveFrames(reconstruction, data);
  const ImuScaleResult result = EstimateImuScale(reconstruction, data.imu, data.noise);
  amplitude = 1.0;
  EXPECT_FALSE(shrunk.spacing_disagrees);
  EXPECT_EQ(shrunk.spaced_scale, 0.0);
  EXPECT_LT(shrunk.scale, 0.9) << shrunk.message;
  EXPECT_TRUE(result.spacing_disagrees) << result.message;
  EXPECT_EQ(result.scale, result.spaced_scale);
  EXPECT_EQ(result.num_pairs, 60);  // 1 s apart
  EXPECT_NEAR(result.scale, 1.0, 3.0 * result.scale_sigma) << result.message;
  EXPECT_NEAR(result.scale, 1.0, 0.02) << result.message;
}

TEST(ImuScale, TooFewFramesOrNoImuIsNotUsable) {
  const Data data = MakeImu(5.0, 6);
  EXPECT_FALSE(
      EstimateImuScale(Reconstruction({1.0, 2.0, 3.0}, 1.0, 7), data.imu, data.noise).usable);
  EXPECT_FALSE(
      EstimateImuScale(Reconstruction({1.0, 2.0, 3.0, 4.0}, 1.0, 7), {}, data.noise).usable);
}

}  // namespace
}  // namespace viosfm

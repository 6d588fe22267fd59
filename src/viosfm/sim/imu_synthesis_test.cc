#include "viosfm/sim/imu_synthesis.h"

#include <gtest/gtest.h>

#include <cmath>

namespace viosfm {
namespace {

Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle));
}

// Dead-reckoning with the trapezoidal rule, the way an IMU-only propagator does.
TEST(ImuSynthesis, NoiseFreeIntegrationReproducesGroundTruth) {
  WalkOptions walk;
  walk.duration_s = 12.0;
  walk.static_start_s = 1.0;
  walk.seed = 3;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions options;
  options.add_noise = false;
  const timestamp_ns_t from = trajectory.start_ns() + SecondsToNs(1.5);
  const timestamp_ns_t to = from + SecondsToNs(10.0);
  const SynthesizedImu imu = SynthesizeImu(trajectory, from, to, options);
  ASSERT_EQ(imu.samples.size(), 2001u);  // 10 s at 200 Hz, both ends included

  const Eigen::Vector3d gravity(0, 0, -kStandardGravity);
  Eigen::Quaterniond rotation = trajectory.WorldFromBody(from).rotation;
  Eigen::Vector3d velocity = trajectory.VelocityInWorld(from);
  Eigen::Vector3d position = trajectory.PositionInWorld(from);
  for (size_t k = 0; k + 1 < imu.samples.size(); ++k) {
    const ImuSample& a = imu.samples[k];
    const ImuSample& b = imu.samples[k + 1];
    const double dt = NsToSeconds(b.timestamp_ns - a.timestamp_ns);
    // Rotation: exponential of the mean rate with a second-order (commutator) term.
    const Eigen::Vector3d mean_rate = 0.5 * (a.gyro + b.gyro);
    const Eigen::Vector3d correction = dt * dt / 12.0 * a.gyro.cross(b.gyro);
    const Eigen::Quaterniond next_rotation =
        (rotation * ExpQuaternion(mean_rate * dt + correction)).normalized();
    const Eigen::Vector3d accel_a = rotation * a.accel + gravity;
    const Eigen::Vector3d accel_b = next_rotation * b.accel + gravity;
    // Acceleration is linear in time between samples to the order used here.
    position += velocity * dt + dt * dt / 6.0 * (2.0 * accel_a + accel_b);
    velocity += 0.5 * dt * (accel_a + accel_b);
    rotation = next_rotation;
  }
  const Rigid3d truth = trajectory.WorldFromBody(to);
  EXPECT_LT((position - truth.translation).norm(), 1e-3) << "position drift over 10 s";
  EXPECT_LT(rotation.angularDistance(truth.rotation), 1e-5);
}

TEST(ImuSynthesis, NoiseHasTheModelledStandardDeviation) {
  WalkOptions walk;
  walk.duration_s = 30.0;
  walk.static_start_s = 29.0;  // static: exact gyro is zero
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions options;
  options.noise.gyro_random_walk = 0.0;
  options.noise.accel_random_walk = 0.0;
  options.initial_gyro_bias = Eigen::Vector3d(0.01, -0.02, 0.03);
  const SynthesizedImu imu = SynthesizeImu(trajectory, trajectory.start_ns(),
                                           trajectory.start_ns() + SecondsToNs(25.0), options);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double sum_sq = 0.0;
  for (const ImuSample& sample : imu.samples) {
    const Eigen::Vector3d noise = sample.gyro - options.initial_gyro_bias;
    sum += noise;
    sum_sq += noise.squaredNorm();
  }
  const double n = static_cast<double>(imu.samples.size());
  const double stddev = std::sqrt(sum_sq / (3 * n));
  EXPECT_NEAR(stddev, options.noise.GyroSampleStddev(), 0.03 * options.noise.GyroSampleStddev());
  EXPECT_LT((sum / n).norm(), 5 * options.noise.GyroSampleStddev() / std::sqrt(n));
  EXPECT_EQ(imu.GyroBiasAt(imu.samples[100].timestamp_ns + 1), options.initial_gyro_bias);
}

TEST(ImuSynthesis, BiasRandomWalkGrowsAsModelled) {
  WalkOptions walk;
  walk.duration_s = 100.0;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions options;
  options.noise.accel_random_walk = 0.01;
  double sum_sq = 0.0;
  const int runs = 40;
  for (int run = 0; run < runs; ++run) {
    options.seed = 100 + run;
    const SynthesizedImu imu = SynthesizeImu(trajectory, trajectory.start_ns(),
                                             trajectory.start_ns() + SecondsToNs(50.0), options);
    sum_sq += imu.accel_bias.back().squaredNorm();
  }
  // Var per axis after T seconds: walk^2 * T.
  const double expected = options.noise.accel_random_walk * std::sqrt(50.0);
  EXPECT_NEAR(std::sqrt(sum_sq / (3 * runs)), expected, 0.25 * expected);
}

// The vibration adds to the accelerometer only, with the RMS asked for and
// no mean (it moves the body by micrometres), from its start on; the gyro,
// the biases and the accelerometer's own noise stay as without it.
TEST(ImuSynthesis, VibrationHasTheModelledRmsAndNothingElseChanges) {
  WalkOptions walk;
  walk.duration_s = 22.0;
  walk.seed = 4;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions options;
  options.seed = 9;
  const SynthesizedImu still = SynthesizeImu(trajectory, trajectory.start_ns(),
                                             trajectory.start_ns() + SecondsToNs(21.0), options);
  options.vibration.accel_rms_mps2 = 1.2;
  options.vibration.start_s = 1.0;
  const SynthesizedImu vibrating = SynthesizeImu(
      trajectory, trajectory.start_ns(), trajectory.start_ns() + SecondsToNs(21.0), options);
  ASSERT_EQ(still.samples.size(), vibrating.samples.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  double n = 0.0;
  for (size_t k = 0; k < still.samples.size(); ++k) {
    EXPECT_EQ(still.samples[k].gyro, vibrating.samples[k].gyro);
    EXPECT_EQ(still.accel_bias[k], vibrating.accel_bias[k]);
    const Eigen::Vector3d difference = vibrating.samples[k].accel - still.samples[k].accel;
    if (vibrating.samples[k].timestamp_ns - trajectory.start_ns() < SecondsToNs(1.0)) {
      EXPECT_EQ(difference, Eigen::Vector3d::Zero());  // before its start
      continue;
    }
    sum += difference;
    sum_sq += difference.cwiseAbs2();
    n += 1.0;
  }
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(std::sqrt(sum_sq[axis] / n), 1.2, 0.06) << "axis " << axis;
    // The mean over 20 s: the broadband part's 1.0 / sqrt(4000), the
    // harmonic lines' far less.
    EXPECT_LT(std::abs(sum[axis] / n), 0.06) << "axis " << axis;
  }
}

}  // namespace
}  // namespace viosfm

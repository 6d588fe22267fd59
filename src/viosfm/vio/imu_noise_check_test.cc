#include "viosfm/vio/imu_noise_check.h"

#include <gtest/gtest.h>

#include "viosfm/sim/sequence_simulator.h"

namespace viosfm {
namespace {

// `room` without images: 2 s static start, then the walk; the calibration
// states the true noise figures times (gyro_scale, accel_scale) (viosfm
// simulate --imu-noise-file-scale).
SimulatedSequence SimulateRoom(double gyro_scale, double accel_scale) {
  SimulationOptions options;
  options.duration_s = 4.0;
  options.render_images = false;
  options.imu_noise_file_scale_gyro = gyro_scale;
  options.imu_noise_file_scale_accel = accel_scale;
  return SimulateSequence(options);
}

StaticInitResult StaticStart(const SimulatedSequence& simulated) {
  const std::vector<ImuSample>& imu = simulated.sequence.imu;
  return DetectStaticStart(imu, imu.front().timestamp_ns, imu.back().timestamp_ns);
}

TEST(CheckImuNoise, MeasuresTheTrueNoiseAtRestAndBoundsWrongFigures) {
  // The real RealSense calibration's errors: the gyro's density 13 times
  // too small, the accelerometer's 30 times too large
  // (`vio-robustness.sh`'s wrong_imu_noise case).
  const SimulatedSequence simulated = SimulateRoom(0.077, 30.0);
  const ImuNoise& truth = simulated.true_imu_noise;
  const ImuNoise& stated = simulated.sequence.rig.imu_noise;
  const StaticInitResult rest = StaticStart(simulated);
  ASSERT_TRUE(rest.is_static()) << rest.message;
  const ImuNoiseCheck check = CheckImuNoise(stated, simulated.sequence.imu, &rest);
  ASSERT_TRUE(check.measured) << check.message;
  // 340 samples a sensor axis at rest (1.7 s): the measured densities are
  // the simulated ones within 10 %.
  EXPECT_NEAR(check.measured_gyro_density / truth.gyro_noise_density, 1.0, 0.1);
  EXPECT_NEAR(check.measured_accel_density / truth.accel_noise_density, 1.0, 0.1);
  // Both densities are brought to the nearest bound of [0.5, 4] times the
  // measurement; the random walks (not measurable in 2 s) are in the MEMS
  // range and stay as stated.
  EXPECT_DOUBLE_EQ(check.used.gyro_noise_density, 0.5 * check.measured_gyro_density);
  EXPECT_DOUBLE_EQ(check.used.accel_noise_density, 4.0 * check.measured_accel_density);
  EXPECT_EQ(check.used.gyro_random_walk, stated.gyro_random_walk);
  EXPECT_EQ(check.used.accel_random_walk, stated.accel_random_walk);
  EXPECT_EQ(check.changes.size(), 2u) << check.message;
}

TEST(CheckImuNoise, KeepsTheTrueFigures) {
  const SimulatedSequence simulated = SimulateRoom(1.0, 1.0);
  const StaticInitResult rest = StaticStart(simulated);
  const ImuNoiseCheck check =
      CheckImuNoise(simulated.sequence.rig.imu_noise, simulated.sequence.imu, &rest);
  EXPECT_TRUE(check.measured);
  EXPECT_TRUE(check.changes.empty()) << check.message;
  EXPECT_EQ(check.used.gyro_noise_density, simulated.true_imu_noise.gyro_noise_density);
  EXPECT_EQ(check.used.accel_noise_density, simulated.true_imu_noise.accel_noise_density);
}

TEST(CheckImuNoise, WithoutAStaticStartClampsIntoTheMemsRange) {
  const SimulatedSequence simulated = SimulateRoom(0.077, 30.0);
  const ImuNoise& stated = simulated.sequence.rig.imu_noise;
  const ImuNoiseCheck check = CheckImuNoise(stated, simulated.sequence.imu, nullptr);
  EXPECT_FALSE(check.measured);
  // Gyro 1.3e-5 is below the MEMS range's 5e-5; accelerometer 0.06 above its 0.05.
  EXPECT_EQ(check.used.gyro_noise_density, 5e-5);
  EXPECT_EQ(check.used.accel_noise_density, 5e-2);
  ImuNoiseCheckOptions off;
  off.enabled = false;
  const ImuNoiseCheck unchecked = CheckImuNoise(stated, simulated.sequence.imu, nullptr, off);
  EXPECT_EQ(unchecked.used.gyro_noise_density, stated.gyro_noise_density);
  EXPECT_EQ(unchecked.used.accel_noise_density, stated.accel_noise_density);
}

}  // namespace
}  // namespace viosfm

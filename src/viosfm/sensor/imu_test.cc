#include "viosfm/sensor/imu.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

using ::testing::StartsWith;

TEST(ImuNoise, DefaultsAreEurocAdis16448) {
  const ImuNoise noise;
  EXPECT_EQ(noise.gyro_noise_density, 1.6968e-4);
  EXPECT_EQ(noise.gyro_random_walk, 1.9393e-5);
  EXPECT_EQ(noise.accel_noise_density, 2.0e-3);
  EXPECT_EQ(noise.accel_random_walk, 3.0e-3);
  EXPECT_EQ(noise.rate_hz, 200.0);
  EXPECT_EQ(noise.Validate(), "");
}

TEST(ImuNoise, DiscreteConversions) {
  ImuNoise noise;
  noise.rate_hz = 400.0;  // sqrt(rate) = 20
  EXPECT_NEAR(noise.GyroSampleStddev(), 1.6968e-4 * 20.0, 1e-18);
  EXPECT_NEAR(noise.AccelSampleStddev(), 2.0e-3 * 20.0, 1e-17);
  EXPECT_NEAR(noise.GyroBiasStepStddev(), 1.9393e-5 / 20.0, 1e-20);
  EXPECT_NEAR(noise.AccelBiasStepStddev(), 3.0e-3 / 20.0, 1e-19);
  // EuRoC at 200 Hz.
  const ImuNoise euroc;
  EXPECT_NEAR(euroc.GyroSampleStddev(), 1.6968e-4 * std::sqrt(200.0), 1e-18);
  EXPECT_NEAR(euroc.AccelBiasStepStddev(), 3.0e-3 / std::sqrt(200.0), 1e-18);
}

TEST(ImuNoise, SampleStddevMatchesIntegratedWhiteNoise) {
  // Averaging continuous white noise of density sigma_c over dt = 1/rate
  // gives a sample with variance sigma_c^2 / dt: simulate it with a fine
  // sub-grid of independent steps and compare the empirical stddev.
  ImuNoise noise;
  noise.rate_hz = 100.0;
  constexpr int kSubsteps = 50;
  constexpr int kSamples = 20000;
  const double dt = 1.0 / noise.rate_hz;
  const double sub_dt = dt / kSubsteps;
  Random random(41);
  double sum_sq = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    double integral = 0.0;  // integral of the noise over the sample period
    for (int k = 0; k < kSubsteps; ++k) {
      integral += random.Normal(0.0, noise.gyro_noise_density * std::sqrt(sub_dt));
    }
    const double sample = integral / dt;  // the average rate over the period
    sum_sq += sample * sample;
  }
  const double empirical = std::sqrt(sum_sq / kSamples);
  // Relative standard error of a stddev estimate: 1 / sqrt(2 N) = 0.5 %.
  EXPECT_NEAR(empirical / noise.GyroSampleStddev(), 1.0, 0.02);
}

TEST(ImuNoise, ValidateNamesTheBadField) {
  ImuNoise noise;
  noise.gyro_noise_density = -1e-4;
  EXPECT_THAT(noise.Validate(), StartsWith("gyro_noise_density"));
  EXPECT_FALSE(noise.Check());
  noise = ImuNoise();
  noise.gyro_random_walk = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(noise.Validate(), StartsWith("gyro_random_walk"));
  noise = ImuNoise();
  noise.accel_noise_density = -2e-3;
  EXPECT_THAT(noise.Validate(), StartsWith("accel_noise_density"));
  noise = ImuNoise();
  noise.accel_random_walk = -1.0;
  EXPECT_THAT(noise.Validate(), StartsWith("accel_random_walk"));
  noise = ImuNoise();
  noise.rate_hz = 0.0;
  EXPECT_THAT(noise.Validate(), StartsWith("rate_hz"));
  noise = ImuNoise();
  noise.gyro_noise_density = 0.0;  // noise-free (simulation) is allowed
  EXPECT_TRUE(noise.Check());
}

TEST(ImuSample, DefaultsAreZero) {
  const ImuSample sample;
  EXPECT_EQ(sample.timestamp_ns, 0);
  EXPECT_EQ(sample.gyro, Eigen::Vector3d::Zero());
  EXPECT_EQ(sample.accel, Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace viosfm

#include "viosfm/vio/imu_noise_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "viosfm/util/random.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {
namespace {

// A still IMU: constant rate and specific force (biases, gravity) plus white
// noise of the given densities (per-sample sigma = density * sqrt(rate)),
// framed by `moving_s` of large oscillating readings before and after, which
// must not enter the measurement over the static part.
struct StaticImu {
  std::vector<ImuSample> samples;
  timestamp_ns_t static_start_ns = 0;
  timestamp_ns_t static_end_ns = 0;
};

StaticImu MakeStaticImu(double gyro_density, double accel_density, double rate_hz, double static_s,
                        double moving_s, uint64_t seed) {
  StaticImu imu;
  Random random(seed);
  const double gyro_sigma = gyro_density * std::sqrt(rate_hz);
  const double accel_sigma = accel_density * std::sqrt(rate_hz);
  const Eigen::Vector3d gyro_bias(0.002, -0.004, 0.001);
  const Eigen::Vector3d specific_force(0.3, -1.2, 9.7);
  const timestamp_ns_t start = 1'000'000'000'000'000'000;
  const int num_moving = static_cast<int>(moving_s * rate_hz);
  const int num_static = static_cast<int>(static_s * rate_hz);
  for (int k = 0; k < 2 * num_moving + num_static; ++k) {
    ImuSample sample;
    sample.timestamp_ns = start + SecondsToNs(k / rate_hz);
    for (int axis = 0; axis < 3; ++axis) {
      sample.gyro[axis] = gyro_bias[axis] + random.Normal(0.0, gyro_sigma);
      sample.accel[axis] = specific_force[axis] + random.Normal(0.0, accel_sigma);
    }
    if (k < num_moving || k >= num_moving + num_static) {
      const double phase = 2.0 * M_PI * 1.5 * k / rate_hz;
      sample.gyro += Eigen::Vector3d(1.0, -0.8, 0.5) * std::sin(phase);
      sample.accel += Eigen::Vector3d(2.0, 1.5, -3.0) * std::cos(phase);
    }
    if (k == num_moving) imu.static_start_ns = sample.timestamp_ns;
    if (k == num_moving + num_static - 1) imu.static_end_ns = sample.timestamp_ns;
    imu.samples.push_back(sample);
  }
  return imu;
}

StaticInitResult StaticInterval(timestamp_ns_t start_ns, timestamp_ns_t end_ns) {
  StaticInitResult result;
  result.status = StaticInitStatus::kStatic;
  result.start_ns = start_ns;
  result.end_ns = end_ns;
  return result;
}

bool Mentions(const std::vector<std::string>& changes, const std::string& name) {
  for (const std::string& change : changes) {
    if (change.find(name) != std::string::npos) return true;
  }
  return false;
}

// The true densities: EuRoC's ADIS16448 figures (the sensor/imu.h defaults).
constexpr double kGyroDensity = 1.6968e-4;  // rad/s/sqrt(Hz)
constexpr double kAccelDensity = 2.0e-3;    // m/s^2/sqrt(Hz)
constexpr double kGyroWalk = 1.9393e-5;     // rad/s^2/sqrt(Hz)
constexpr double kAccelWalk = 3.0e-3;       // m/s^3/sqrt(Hz)

// The RealSense file's white-noise densities, with the given walks.
ImuNoise RealSenseFileDensities(double gyro_walk, double accel_walk) {
  ImuNoise noise;
  noise.gyro_noise_density = 3.7e-5;
  noise.accel_noise_density = 0.183;
  noise.gyro_random_walk = gyro_walk;
  noise.accel_random_walk = accel_walk;
  return noise;
}

TEST(ImuNoiseCheck, OptionsValidate) {
  EXPECT_EQ(ImuNoiseCheckOptions().Validate(), "");
  ImuNoiseCheckOptions options;
  options.min_ratio = 0.0;
  EXPECT_NE(options.Validate().find("min_ratio"), std::string::npos);
  options.min_ratio = 1.5;
  EXPECT_NE(options.Validate().find("min_ratio"), std::string::npos);
  options = ImuNoiseCheckOptions();
  options.max_ratio = 0.9;
  EXPECT_NE(options.Validate().find("max_ratio"), std::string::npos);
  options = ImuNoiseCheckOptions();
  options.min_static_s = 0.0;
  EXPECT_NE(options.Validate().find("min_static_s"), std::string::npos);
  EXPECT_FALSE(options.Check());
}

// Known densities at 200 and 800 Hz (the per-sample sigma doubles, the
// density does not), 2 s at rest between oscillating readings: recovered
// within 10 % (a standard deviation from 400 samples scatters by 3.5 % per
// axis, 2 % averaged over three).
TEST(ImuNoiseCheck, MeasuresTheWhiteNoiseDensity) {
  for (const double rate_hz : {200.0, 800.0}) {
    for (const uint64_t seed : {1, 2, 3}) {
      const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, rate_hz, 2.0, 1.0, seed);
      const auto [gyro, accel] =
          MeasureWhiteNoiseDensities(imu.samples, imu.static_start_ns, imu.static_end_ns);
      std::cout << rate_hz << " Hz, seed " << seed << ": gyro " << gyro / kGyroDensity
                << " x truth, accel " << accel / kAccelDensity << " x truth\n";
      EXPECT_NEAR(gyro / kGyroDensity, 1.0, 0.1);
      EXPECT_NEAR(accel / kAccelDensity, 1.0, 0.1);
    }
  }
  // Over the whole range the oscillation dominates.
  const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, 200.0, 2.0, 1.0, 4);
  const auto [gyro_all, accel_all] = MeasureWhiteNoiseDensities(
      imu.samples, imu.samples.front().timestamp_ns, imu.samples.back().timestamp_ns);
  EXPECT_GT(gyro_all, 10.0 * kGyroDensity);
  EXPECT_GT(accel_all, 10.0 * kAccelDensity);
  // Fewer than 10 samples: no measurement.
  const auto [gyro_few, accel_few] = MeasureWhiteNoiseDensities(imu.samples, imu.static_start_ns,
                                                                imu.samples[200 + 8].timestamp_ns);
  EXPECT_EQ(gyro_few, 0.0);
  EXPECT_EQ(accel_few, 0.0);
}

// With a static interval: a plausible file figure is kept; one 13 times too
// small (the RealSense file's gyro) is raised to min_ratio times the
// measured density, one 30 times too large (its accelerometer) lowered to
// max_ratio times it.
TEST(ImuNoiseCheck, BoundsTheFileFiguresByTheMeasuredNoise) {
  const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, 200.0, 2.0, 1.0, 5);
  const StaticInitResult interval = StaticInterval(imu.static_start_ns, imu.static_end_ns);
  const ImuNoiseCheckOptions options;  // ratios 0.5 and 4

  ImuNoise plausible;
  plausible.gyro_noise_density = 2.0 * kGyroDensity;  // inflated, as configurations do
  plausible.accel_noise_density = 0.7 * kAccelDensity;
  const ImuNoiseCheck kept = CheckImuNoise(plausible, imu.samples, &interval, options);
  std::cout << kept.message << "\n";
  EXPECT_TRUE(kept.measured);
  EXPECT_NEAR(kept.measured_gyro_density / kGyroDensity, 1.0, 0.1);
  EXPECT_NEAR(kept.measured_accel_density / kAccelDensity, 1.0, 0.1);
  EXPECT_TRUE(kept.changes.empty()) << kept.message;
  EXPECT_EQ(kept.used.gyro_noise_density, plausible.gyro_noise_density);
  EXPECT_EQ(kept.used.accel_noise_density, plausible.accel_noise_density);
  EXPECT_EQ(kept.used.gyro_random_walk, plausible.gyro_random_walk);
  EXPECT_EQ(kept.used.accel_random_walk, plausible.accel_random_walk);

  // Each sensor's two figures wrong by one factor, as when a file's source
  // scaled both.
  ImuNoise wrong = plausible;
  wrong.gyro_noise_density = kGyroDensity / 13.0;
  wrong.gyro_random_walk = kGyroWalk / 13.0;
  wrong.accel_noise_density = 30.0 * kAccelDensity;
  wrong.accel_random_walk = 30.0 * kAccelWalk;
  const ImuNoiseCheck bounded = CheckImuNoise(wrong, imu.samples, &interval, options);
  std::cout << bounded.message << "\n";
  ASSERT_TRUE(bounded.measured);
  EXPECT_DOUBLE_EQ(bounded.used.gyro_noise_density,
                   options.min_ratio * bounded.measured_gyro_density);
  EXPECT_DOUBLE_EQ(bounded.used.accel_noise_density,
                   options.max_ratio * bounded.measured_accel_density);
  // Against the truth: 0.5 and 4 times the true densities, within 10 %.
  EXPECT_NEAR(bounded.used.gyro_noise_density / (0.5 * kGyroDensity), 1.0, 0.1);
  EXPECT_NEAR(bounded.used.accel_noise_density / (4.0 * kAccelDensity), 1.0, 0.1);
  EXPECT_EQ(bounded.given.gyro_noise_density, wrong.gyro_noise_density);
  EXPECT_EQ(bounded.given.accel_noise_density, wrong.accel_noise_density);
  // The random walks follow their densities: 0.5 and 4 times the true
  // walks, within the densities' 10 %.
  EXPECT_DOUBLE_EQ(
      bounded.used.gyro_random_walk,
      wrong.gyro_random_walk * bounded.used.gyro_noise_density / wrong.gyro_noise_density);
  EXPECT_NEAR(bounded.used.gyro_random_walk / (0.5 * kGyroWalk), 1.0, 0.1);
  EXPECT_NEAR(bounded.used.accel_random_walk / (4.0 * kAccelWalk), 1.0, 0.1);
  EXPECT_EQ(bounded.changes.size(), 4u) << bounded.message;
  EXPECT_TRUE(Mentions(bounded.changes, "gyroscope_noise_density"));
  EXPECT_TRUE(Mentions(bounded.changes, "accelerometer_noise_density"));
  EXPECT_TRUE(Mentions(bounded.changes, "gyroscope_random_walk"));
  EXPECT_TRUE(Mentions(bounded.changes, "accelerometer_random_walk"));
  // Unless told to leave them.
  ImuNoiseCheckOptions walks_as_given;
  walks_as_given.scale_random_walks = false;
  const ImuNoiseCheck unscaled = CheckImuNoise(wrong, imu.samples, &interval, walks_as_given);
  EXPECT_EQ(unscaled.used.accel_noise_density, bounded.used.accel_noise_density);
  EXPECT_EQ(unscaled.used.gyro_random_walk, wrong.gyro_random_walk);
  EXPECT_EQ(unscaled.used.accel_random_walk, wrong.accel_random_walk);
  EXPECT_EQ(unscaled.changes.size(), 2u) << unscaled.message;

  // Other ratios move the bounds with them.
  ImuNoiseCheckOptions wide;
  wide.min_ratio = 0.05;
  wide.max_ratio = 40.0;
  const ImuNoiseCheck wide_check = CheckImuNoise(wrong, imu.samples, &interval, wide);
  EXPECT_TRUE(wide_check.changes.empty()) << wide_check.message;
  EXPECT_EQ(wide_check.used.gyro_noise_density, wrong.gyro_noise_density);
  EXPECT_EQ(wide_check.used.accel_noise_density, wrong.accel_noise_density);
}

// Without a usable static interval (none, not static, or shorter than
// min_static_s) the densities are clamped into the MEMS ranges of the
// header (gyro 5e-5 to 1e-2, accel 5e-4 to 5e-2), and random walks, scaled
// with them, into theirs (gyro 1e-7 to 1e-2, accel 1e-6 to 1e-1).
// (The stream moves throughout here, so that its quietest stretch bounds
// nothing.)
TEST(ImuNoiseCheck, WithoutRestClampsIntoTheMemsRanges) {
  const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, 200.0, 0.0, 1.5, 6);
  const ImuNoise wrong = RealSenseFileDensities(1e-9, 1.0);
  StaticInitResult moving = StaticInterval(imu.static_start_ns, imu.static_end_ns);
  moving.status = StaticInitStatus::kNotStatic;
  const StaticInitResult too_short =
      StaticInterval(imu.static_start_ns, imu.static_start_ns + SecondsToNs(0.4));
  const std::vector<const StaticInitResult*> intervals = {nullptr, &moving, &too_short};
  for (const StaticInitResult* interval : intervals) {
    const ImuNoiseCheck check = CheckImuNoise(wrong, imu.samples, interval);
    std::cout << check.message << "\n";
    EXPECT_FALSE(check.measured);
    EXPECT_DOUBLE_EQ(check.used.gyro_noise_density, 5e-5);
    EXPECT_DOUBLE_EQ(check.used.accel_noise_density, 5e-2);
    EXPECT_DOUBLE_EQ(check.used.gyro_random_walk, 1e-7);
    EXPECT_DOUBLE_EQ(check.used.accel_random_walk, 1e-1);
    EXPECT_EQ(check.changes.size(), 6u) << check.message;  // 2 clamped, 2 scaled and clamped
  }
  // The other ends of the ranges.
  ImuNoise high;
  high.gyro_noise_density = 0.5;
  high.accel_noise_density = 1e-5;
  high.gyro_random_walk = 0.5;
  high.accel_random_walk = 1e-8;
  const ImuNoiseCheck high_check = CheckImuNoise(high, imu.samples, nullptr);
  EXPECT_DOUBLE_EQ(high_check.used.gyro_noise_density, 1e-2);
  EXPECT_DOUBLE_EQ(high_check.used.accel_noise_density, 5e-4);
  EXPECT_DOUBLE_EQ(high_check.used.gyro_random_walk, 1e-2);
  EXPECT_DOUBLE_EQ(high_check.used.accel_random_walk, 1e-6);
  // The sensor/imu.h defaults (EuRoC's data sheet) lie inside every range.
  const ImuNoiseCheck euroc = CheckImuNoise(ImuNoise(), imu.samples, nullptr);
  EXPECT_TRUE(euroc.changes.empty()) << euroc.message;
  // A 0.4 s interval counts once min_static_s allows it.
  ImuNoiseCheckOptions short_ok;
  short_ok.min_static_s = 0.3;
  const ImuNoiseCheck measured = CheckImuNoise(wrong, imu.samples, &too_short, short_ok);
  EXPECT_TRUE(measured.measured) << measured.message;
}

// Without a static start, the quietest half second of the stream bounds the
// white noise from above: a stream with a 2 s still stretch in its middle
// (not declared a static start) bounds the accelerometer density at the
// true one within 15 %, and a file's 0.18 is lowered to that bound; a
// figure already below the bound is kept. Motion only adds to the spread,
// so the bound is below the truth by no more than the scatter of the
// lowest of several windows' estimates (measured 11 % here, 4 % a window).
TEST(ImuNoiseCheck, WithoutRestTheQuietestStretchBoundsTheNoise) {
  const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, 200.0, 2.0, 1.0, 7);
  const ImuNoise wrong = RealSenseFileDensities(2.6e-6, 0.0245);
  const ImuNoiseCheck check = CheckImuNoise(wrong, imu.samples, nullptr);
  std::cout << check.message << "\n";
  EXPECT_FALSE(check.measured);
  EXPECT_GE(check.bound_start_ns, imu.static_start_ns);
  EXPECT_LE(check.bound_start_ns + SecondsToNs(0.5), imu.static_end_ns + SecondsToNs(0.01));
  EXPECT_NEAR(check.bound_accel_density, kAccelDensity, 0.15 * kAccelDensity);
  EXPECT_NEAR(check.bound_gyro_density, kGyroDensity, 0.15 * kGyroDensity);
  EXPECT_DOUBLE_EQ(check.used.accel_noise_density, check.bound_accel_density);
  // The walk scaled by the same factor as its density.
  EXPECT_NEAR(check.used.accel_random_walk,
              0.0245 * check.used.accel_noise_density / wrong.accel_noise_density, 1e-12);
  // The gyro figure, below the MEMS range, is raised to it, which the bound
  // (1.7e-4) leaves alone.
  EXPECT_DOUBLE_EQ(check.used.gyro_noise_density, 5e-5);
  EXPECT_TRUE(Mentions(check.changes, "quietest"));

  // A file figure below the bound is kept.
  ImuNoise plausible;
  plausible.accel_noise_density = 1.0e-3;
  const ImuNoiseCheck kept = CheckImuNoise(plausible, imu.samples, nullptr);
  EXPECT_DOUBLE_EQ(kept.used.accel_noise_density, 1.0e-3) << kept.message;
}

// Disabled: the file's figures, however implausible, are used as they are.
TEST(ImuNoiseCheck, DisabledKeepsTheFileFigures) {
  const StaticImu imu = MakeStaticImu(kGyroDensity, kAccelDensity, 200.0, 2.0, 1.0, 7);
  const StaticInitResult interval = StaticInterval(imu.static_start_ns, imu.static_end_ns);
  ImuNoise wrong;
  wrong.gyro_noise_density = 1e-7;
  wrong.accel_noise_density = 5.0;
  wrong.gyro_random_walk = 1.0;
  wrong.accel_random_walk = 1e-9;
  ImuNoiseCheckOptions disabled;
  disabled.enabled = false;
  const ImuNoiseCheck check = CheckImuNoise(wrong, imu.samples, &interval, disabled);
  EXPECT_FALSE(check.measured);
  EXPECT_TRUE(check.changes.empty());
  EXPECT_EQ(check.used.gyro_noise_density, wrong.gyro_noise_density);
  EXPECT_EQ(check.used.accel_noise_density, wrong.accel_noise_density);
  EXPECT_EQ(check.used.gyro_random_walk, wrong.gyro_random_walk);
  EXPECT_EQ(check.used.accel_random_walk, wrong.accel_random_walk);
  EXPECT_NE(check.message.find("unchecked"), std::string::npos) << check.message;
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sim/imu_synthesis.h"

#include <algorithm>
#include <cmath>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

size_t SampleIndexAt(const ImuSamples& samples, timestamp_ns_t t) {
  VIOSFM_CHECK(!samples.empty());
  const auto it = std::upper_bound(
      samples.begin(), samples.end(), t,
      [](timestamp_ns_t value, const ImuSample& sample) { return value < sample.timestamp_ns; });
  return it == samples.begin() ? 0 : static_cast<size_t>(it - samples.begin() - 1);
}

Eigen::Vector3d NormalVector(Random& random, double stddev) {
  return Eigen::Vector3d(random.Normal(0.0, stddev), random.Normal(0.0, stddev),
                         random.Normal(0.0, stddev));
}

}  // namespace

Eigen::Vector3d SynthesizedImu::GyroBiasAt(timestamp_ns_t t) const {
  return gyro_bias[SampleIndexAt(samples, t)];
}

Eigen::Vector3d SynthesizedImu::AccelBiasAt(timestamp_ns_t t) const {
  return accel_bias[SampleIndexAt(samples, t)];
}

SynthesizedImu SynthesizeImu(const BodyTrajectory& trajectory, timestamp_ns_t from,
                             timestamp_ns_t to, const ImuSynthesisOptions& options) {
  VIOSFM_CHECK(options.Check()) << options.Validate();
  VIOSFM_CHECK_LE(from, to);
  const ImuNoise& noise = options.noise;
  const double period_ns = 1e9 / noise.rate_hz;
  Random random(options.seed);
  SynthesizedImu imu;
  Eigen::Vector3d gyro_bias = options.initial_gyro_bias;
  Eigen::Vector3d accel_bias = options.initial_accel_bias;
  // Sample k is at start + round(k * period): a fixed grid independent of `from`.
  const timestamp_ns_t start = trajectory.start_ns();
  int64_t k = static_cast<int64_t>(std::ceil((from - start) / period_ns - 1e-9));
  for (;; ++k) {
    const timestamp_ns_t t = start + static_cast<timestamp_ns_t>(std::llround(k * period_ns));
    if (t < from) continue;
    if (t > to) break;
    ImuSample sample;
    sample.timestamp_ns = t;
    sample.gyro = trajectory.AngularVelocityInBody(t) + gyro_bias;
    sample.accel = trajectory.SpecificForceInBody(t) + accel_bias;
    if (options.add_noise) {
      sample.gyro += NormalVector(random, noise.GyroSampleStddev());
      sample.accel += NormalVector(random, noise.AccelSampleStddev());
    }
    imu.samples.push_back(sample);
    imu.gyro_bias.push_back(gyro_bias);
    imu.accel_bias.push_back(accel_bias);
    if (options.add_noise) {
      gyro_bias += NormalVector(random, noise.GyroBiasStepStddev());
      accel_bias += NormalVector(random, noise.AccelBiasStepStddev());
    }
  }
  return imu;
}

}  // namespace viosfm

#include "viosfm/sim/imu_synthesis.h"

#include <algorithm>
#include <cmath>

#include "viosfm/sim/scene_model.h"
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

std::string ImuVibrationOptions::Validate() const {
  if (!(accel_rms_mps2 >= 0.0)) return "accel_rms_mps2 must be >= 0";
  if (!(broadband_fraction >= 0.0 && broadband_fraction <= 1.0)) {
    return "broadband_fraction must be in [0, 1]";
  }
  if (!(min_frequency_hz > 0.0) || !(max_frequency_hz >= min_frequency_hz)) {
    return "min_frequency_hz/max_frequency_hz must satisfy 0 < min <= max";
  }
  if (num_components < 1) return "num_components must be >= 1";
  if (!(frequency_wander_hz >= 0.0) || frequency_wander_hz >= min_frequency_hz) {
    return "frequency_wander_hz must be in [0, min_frequency_hz)";
  }
  if (!(wander_period_s > 0.0)) return "wander_period_s must be > 0";
  if (!(start_s >= 0.0)) return "start_s must be >= 0";
  return "";
}

ImuVibration::ImuVibration(const ImuVibrationOptions& options) {
  if (!(options.accel_rms_mps2 > 0.0)) return;
  Random random(options.seed);
  // Equal amplitudes: a sinusoid of amplitude a has RMS a / sqrt(2).
  const double amplitude =
      options.accel_rms_mps2 *
      std::sqrt(2.0 * (1.0 - options.broadband_fraction) / options.num_components);
  for (int axis = 0; axis < 3; ++axis) {
    for (int k = 0; k < options.num_components; ++k) {
      Component component;
      component.axis = axis;
      component.amplitude = amplitude;
      component.frequency_hz = random.Uniform(options.min_frequency_hz, options.max_frequency_hz);
      component.wander_hz = options.frequency_wander_hz;
      component.wander_period_s = options.wander_period_s * random.Uniform(0.7, 1.3);
      component.wander_phase = random.Uniform(0.0, 2.0 * M_PI);
      component.phase = random.Uniform(0.0, 2.0 * M_PI);
      components_.push_back(component);
    }
  }
}

Eigen::Vector3d ImuVibration::HarmonicAccelAt(double t) const {
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  for (const Component& c : components_) {
    // The phase integrates f(t) = f0 + w sin(2 pi t / T + psi).
    const double omega = 2.0 * M_PI / c.wander_period_s;
    const double cycles =
        c.frequency_hz * t -
        c.wander_hz / omega * (std::cos(omega * t + c.wander_phase) - std::cos(c.wander_phase));
    accel[c.axis] += c.amplitude * std::sin(2.0 * M_PI * cycles + c.phase);
  }
  return accel;
}

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
  const ImuVibration vibration(options.vibration);
  // The broadband vibration's own stream: the other readings stay as without it.
  Random vibration_random(MixSeed(options.vibration.seed, 1));
  const double broadband_stddev =
      options.vibration.accel_rms_mps2 * std::sqrt(options.vibration.broadband_fraction);
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
    if (options.vibration.accel_rms_mps2 > 0.0 &&
        t - start >= SecondsToNs(options.vibration.start_s)) {
      sample.accel += vibration.HarmonicAccelAt(NsToSeconds(t - start)) +
                      NormalVector(vibration_random, broadband_stddev);
    }
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

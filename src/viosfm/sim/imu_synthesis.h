// IMU measurements synthesised from a BodyTrajectory: exact angular velocity
// and specific force (gravity included) plus discrete white noise and bias
// random walks from an ImuNoise model.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/sensor/imu.h"
#include "viosfm/sim/trajectory.h"

namespace viosfm {

// Vibration of a flying platform (propellers, motors, the frame's
// resonances) in the accelerometer's readings, accel_rms_mps2 RMS a axis in
// all: a broadband part (broadband_fraction of the power), independent from
// reading to reading as the 200 Hz sampling leaves a spread spectrum, and
// harmonic lines, per axis num_components sinusoids whose frequencies lie
// in [min_frequency_hz, max_frequency_hz] and wander by
// +-frequency_wander_hz over about wander_period_s (the motors follow the
// thrust), aliased by the sampling, from start_s on. The body's displacement by it
// (micrometres) is not modelled; the truth stays the smooth motion.
struct ImuVibrationOptions {
  double accel_rms_mps2 = 0.0;  // m/s^2 per axis; 0 (default): none
  double broadband_fraction = 0.7;
  double min_frequency_hz = 60.0;
  double max_frequency_hz = 190.0;
  int num_components = 4;
  double frequency_wander_hz = 10.0;
  double wander_period_s = 3.0;
  // s after the trajectory's start from which it vibrates (a drone standing
  // before take-off has its motors off). Default 0.
  double start_s = 0.0;
  uint64_t seed = 7;

  std::string Validate() const;  // empty if valid, else names the bad field
};

// The harmonic lines of the vibration (m/s^2, body frame) at t seconds
// after the start.
class ImuVibration {
 public:
  explicit ImuVibration(const ImuVibrationOptions& options);
  Eigen::Vector3d HarmonicAccelAt(double t) const;

 private:
  struct Component {
    int axis = 0;
    double amplitude = 0.0;        // m/s^2
    double frequency_hz = 0.0;     // mean
    double wander_hz = 0.0;        // amplitude of the wander
    double wander_period_s = 1.0;  // s
    double wander_phase = 0.0;     // rad
    double phase = 0.0;            // rad
  };
  std::vector<Component> components_;
};

struct ImuSynthesisOptions {
  ImuNoise noise;         // densities and random walks; noise.rate_hz is the sample rate
  bool add_noise = true;  // false: exact measurements with constant initial biases
  Eigen::Vector3d initial_gyro_bias = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d initial_accel_bias = Eigen::Vector3d::Zero();  // m/s^2
  uint64_t seed = 1;
  ImuVibrationOptions vibration;  // default: none

  std::string Validate() const {
    if (const std::string error = noise.Validate(); !error.empty()) return error;
    if (const std::string error = vibration.Validate(); !error.empty()) return "vibration." + error;
    return "";
  }
  bool Check() const { return Validate().empty(); }
};

struct SynthesizedImu {
  ImuSamples samples;
  // True biases at each sample (what the noisy measurement contains).
  std::vector<Eigen::Vector3d> gyro_bias;
  std::vector<Eigen::Vector3d> accel_bias;

  // Biases at time t (from the latest sample not after t).
  Eigen::Vector3d GyroBiasAt(timestamp_ns_t t) const;
  Eigen::Vector3d AccelBiasAt(timestamp_ns_t t) const;
};

// Samples at start_ns + k / rate for every instant inside [from, to].
SynthesizedImu SynthesizeImu(const BodyTrajectory& trajectory, timestamp_ns_t from,
                             timestamp_ns_t to, const ImuSynthesisOptions& options);

}  // namespace viosfm

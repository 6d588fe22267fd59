// IMU measurements synthesised from a BodyTrajectory: exact angular velocity
// and specific force (gravity included) plus discrete white noise and bias
// random walks from an ImuNoise model.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/sensor/imu.h"
#include "viosfm/sim/trajectory.h"

namespace viosfm {

struct ImuSynthesisOptions {
  ImuNoise noise;         // densities and random walks; noise.rate_hz is the sample rate
  bool add_noise = true;  // false: exact measurements with constant initial biases
  Eigen::Vector3d initial_gyro_bias = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d initial_accel_bias = Eigen::Vector3d::Zero();  // m/s^2
  uint64_t seed = 1;

  std::string Validate() const { return noise.Validate(); }
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

// IMU measurements and noise model.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/util/timestamp.h"

namespace viosfm {

// Gravity magnitude (m/s^2). viosfm's world frames are z up, gravity along -z:
// the world gravity vector is (0, 0, -kStandardGravity).
inline constexpr double kStandardGravity = 9.81;

// One IMU reading, in the IMU (body) frame.
struct ImuSample {
  timestamp_ns_t timestamp_ns = 0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // angular velocity, rad/s
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // specific force, m/s^2 (gravity included)
};

// Continuous-time noise parameters, as Kalibr/EuRoC imu0/sensor.yaml states
// them. Defaults: EuRoC's ADIS16448 figures.
struct ImuNoise {
  double gyro_noise_density = 1.6968e-4;  // rad / s / sqrt(Hz)
  double gyro_random_walk = 1.9393e-5;    // rad / s^2 / sqrt(Hz)
  double accel_noise_density = 2.0e-3;    // m / s^2 / sqrt(Hz)
  double accel_random_walk = 3.0e-3;      // m / s^3 / sqrt(Hz)
  double rate_hz = 200.0;                 // sampling rate, Hz

  // Standard deviation of one discrete sample's white noise: density * sqrt(rate).
  double GyroSampleStddev() const;
  double AccelSampleStddev() const;
  // Standard deviation of the bias change over one sample period: walk / sqrt(rate).
  double GyroBiasStepStddev() const;
  double AccelBiasStepStddev() const;

  // Empty if valid; otherwise names the bad field and why.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

using ImuSamples = std::vector<ImuSample>;

}  // namespace viosfm

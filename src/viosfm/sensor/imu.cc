#include "viosfm/sensor/imu.h"

#include <cmath>

namespace viosfm {

double ImuNoise::GyroSampleStddev() const {
  return gyro_noise_density * std::sqrt(rate_hz);
}
double ImuNoise::AccelSampleStddev() const {
  return accel_noise_density * std::sqrt(rate_hz);
}
double ImuNoise::GyroBiasStepStddev() const {
  return gyro_random_walk / std::sqrt(rate_hz);
}
double ImuNoise::AccelBiasStepStddev() const {
  return accel_random_walk / std::sqrt(rate_hz);
}

std::string ImuNoise::Validate() const {
  if (!(gyro_noise_density >= 0)) return "gyro_noise_density must be >= 0";
  if (!(gyro_random_walk >= 0)) return "gyro_random_walk must be >= 0";
  if (!(accel_noise_density >= 0)) return "accel_noise_density must be >= 0";
  if (!(accel_random_walk >= 0)) return "accel_random_walk must be >= 0";
  if (!(rate_hz > 0)) return "rate_hz must be > 0";
  return "";
}

}  // namespace viosfm

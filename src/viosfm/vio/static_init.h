// Static initialisation from the IMU alone: detects that the platform stands
// still from the start, and estimates from the static interval
//  - the gravity direction in the body frame (hence roll and pitch; the yaw
//    is unobservable and set to zero),
//  - the gyro bias (the mean angular rate; the Earth's rotation, about
//    7.3e-5 rad/s, is below the gyro noise and is not modelled),
//  - the only observable part of the accel bias: its component along the
//    measured specific force. At rest the accelerometer reads
//    R^T * (0, 0, |g|) + ba; a bias component perpendicular to gravity is
//    indistinguishable from a small tilt (it goes into roll/pitch, an error
//    of |ba_perp| / |g| rad), and only the norm of the reading, |g| + ba . u,
//    tells the bias along the up direction u.
//
// Detection: windows of window_s slide from `from` by step_s. Within a
// window the readings are averaged over blocks of smoothing_s, and the window
// is static when these block means scatter less than the thresholds about the
// window mean, the mean rate is below max_gyro_norm and the mean specific
// force is close to gravity. The block averaging matters on real platforms:
// a MAV on the ground with its rotors spinning (EuRoC) vibrates with a raw
// accel scatter of 0.2 to 1.8 m/s^2, as large as in flight, while its 0.1 s
// means scatter by 0.05 to 0.11 m/s^2 (and its gyro means by 0.005 to 0.009
// rad/s, against 0.05 to 0.35 rad/s in flight). The static interval is the
// union of the consecutive static windows from `from` (the first window must
// be static). A gentle onset of motion stays under the thresholds for a
// while, so when motion (not the end of the range) ends the interval, its
// last motion_margin_s are dropped.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct StaticInitOptions {
  // s, length of one detection window, also the shortest static interval
  // accepted. Default 1.0.
  double window_s = 1.0;
  // s, shift between consecutive windows. Default 0.1.
  double step_s = 0.1;
  // s, readings are averaged over blocks of this length before their scatter
  // is measured (suppresses vibration). Default 0.1.
  double smoothing_s = 0.1;
  // m/s^2, largest RMS deviation of the block-mean accel vectors from the
  // window mean (sqrt of the trace of their covariance). Default 0.25
  // (EuRoC at rest with rotors spinning: up to 0.11).
  double max_accel_stddev = 0.25;
  // rad/s, the same for the gyro. Default 0.03 (EuRoC at rest: up to 0.009;
  // in flight: 0.05 and more).
  double max_gyro_stddev = 0.03;
  // rad/s, largest norm of the mean gyro reading of a window; must exceed the
  // gyro bias (EuRoC: up to 0.08). Default 0.2.
  double max_gyro_norm = 0.2;
  // m/s^2, largest | |mean accel| - gravity | of a window. Default 1.0.
  double max_gravity_norm_error = 1.0;
  // m/s^2, gravity magnitude. Default 9.81.
  double gravity_magnitude = 9.81;
  // s, dropped from the end of a static interval that motion ends (see
  // above). Default 0.5.
  double motion_margin_s = 0.5;
  // s, shortest static interval accepted once motion_margin_s is dropped.
  // Default 0.5 (0.5 s at 200 Hz gives the gyro bias to a few 1e-4 rad/s).
  double min_static_s = 0.5;
  // s, IMU readings this long before the first image are searched for the
  // static interval too (recorders often start the IMU first; a static
  // interval that ends before the first image is carried to it by the IMU).
  // Default 10.
  double lookback_s = 10.0;
  // s, a static interval that ends longer than this before the first image
  // is not used (the IMU alone would carry the state too far). Default 2.
  double max_propagation_s = 2.0;
  // Estimate the accel bias along gravity (true) or leave it zero. Default true.
  bool estimate_accel_bias_along_gravity = true;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

enum class StaticInitStatus {
  kStatic,         // a static interval starts at `from`; the estimates are set
  kNotStatic,      // the first window moves
  kNotEnoughData,  // fewer than one window of samples in [from, to]
};
const char* StaticInitStatusName(StaticInitStatus status);

struct StaticInitResult {
  StaticInitStatus status = StaticInitStatus::kNotEnoughData;
  // The static interval (stamps of its first and last samples) on which the
  // estimates are computed.
  timestamp_ns_t start_ns = 0;
  timestamp_ns_t end_ns = 0;
  int num_samples = 0;
  // Unit vector opposite to gravity (the mean specific force direction), body frame.
  Eigen::Vector3d up_in_body = Eigen::Vector3d::UnitZ();
  // -gravity_magnitude * up_in_body, m/s^2.
  Eigen::Vector3d gravity_in_body = Eigen::Vector3d(0.0, 0.0, -9.81);
  // Roll and pitch of world_from_body = Rz(0) Ry(pitch) Rx(roll), rad.
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  // Rotation only (zero yaw, zero translation): maps up_in_body to world +z.
  Rigid3d world_from_body;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  // rad/s
  // The component along up_in_body only (see above), m/s^2.
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  // Statistics of the whole interval (block-smoothed, as for the thresholds).
  double accel_stddev = 0.0;  // m/s^2
  double gyro_stddev = 0.0;   // rad/s
  // The statistics of the interval, or for kNotStatic of the first window, or
  // why there is not enough data.
  std::string message;

  bool is_static() const { return status == StaticInitStatus::kStatic; }
};

// Looks for a static interval starting at the first sample at or after
// `from`, within [from, to]. Samples must be ordered by increasing stamp.
StaticInitResult DetectStaticStart(const std::vector<ImuSample>& samples, timestamp_ns_t from,
                                   timestamp_ns_t to, const StaticInitOptions& options = {});

// Roll and pitch (rad) of the rotation Ry(pitch) Rx(roll) that maps `up_in_body`
// (normalised inside) to the world +z, and that rotation.
Eigen::Quaterniond GravityAlignedRotation(const Eigen::Vector3d& up_in_body, double* roll_rad,
                                          double* pitch_rad);

}  // namespace viosfm

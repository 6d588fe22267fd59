// A trajectory's rotations checked against the gyro, for recordings without
// ground truth.
//
// Over a second a MEMS gyro integrates to a relative rotation a few
// hundredths of a degree from the truth once its bias is removed (white
// noise of 1e-4 to 4e-4 rad/s/sqrt(Hz) adds 0.006 to 0.02 degrees; the
// bias's walk less), while a reconstruction that the images bent turns
// by degrees where it should not. So the camera's relative rotation
// between frames about `interval_s` apart, from the trajectory, is compared
// with the gyro's between the same stamps, expressed in the camera through
// the camera-IMU rotation of the calibration and on the IMU's clock through
// its time offset. The gyro is integrated here (the midpoint rule on its
// samples), not by the VIO's preintegration: the judge shares no code with
// what it judges. Its bias is one constant, fitted by least squares to the
// trajectory's own relative rotations and fitted again without the
// intervals more than three times the median error off, so that a bend is
// not spread over the recording as a bias; or it is taken as zero (the raw
// gyro). A fitted bias can take up part of a slow, even turn of a bent
// trajectory (three numbers for the whole recording), not a bend of a few
// seconds: what remains is the trajectory's error, or the rig's (the
// camera-IMU rotation, the time offset, rolling shutter) where the
// intervals share it.
//
// The check judges a trajectory made without the gyro (COLMAP's, or any
// images-only model) independently; a trajectory made with it (a VIO's,
// viosfm run's with its gyro priors, sfm/gyro_priors.h) only for its
// consistency with it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "viosfm/eval/traj_eval.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct GyroCheckOptions {
  // s, the relative rotations compared are those between a frame and the
  // first frame at least this much later (intervals end to end, none
  // overlapping). Default 1.
  double interval_s = 1.0;
  // An interval longer than this many times interval_s (a gap in the
  // trajectory) is not compared. Default 2.
  double max_interval_factor = 2.0;
  // Fit one constant gyro bias to the trajectory's rotations (else the raw
  // gyro, bias zero). Default true.
  bool fit_bias = true;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

struct GyroCheckInterval {
  timestamp_ns_t from_ns = 0;  // the two frames' stamps, on the camera's clock
  timestamp_ns_t to_ns = 0;
  double gyro_angle_deg = 0.0;  // the gyro's rotation over the interval
  double error_deg = 0.0;       // the angle between the trajectory's and the gyro's
};

struct GyroCheckResult {
  size_t num_frames = 0;
  std::vector<GyroCheckInterval> intervals;
  // Intervals not compared: a part outside the IMU's samples, or longer
  // than max_interval_factor * interval_s.
  size_t num_without_imu = 0;
  size_t num_gaps = 0;
  timestamp_ns_t time_offset_ns = 0;  // the rig's: t_imu = t_cam + offset
  bool bias_fitted = false;
  // The intervals the bias was fitted to: those within three times the
  // median error (and 0.05 degrees) of the fit to all, fitted again.
  size_t num_bias_intervals = 0;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  // rad/s, the IMU's axes
  ErrorStatistics error_deg;
};

// `world_from_cam`: camera poses (stamps on the camera's clock); `rig`
// gives body_from_cam (body = IMU) and the camera-IMU time offset; `imu` in
// increasing time (an interval across a gap of more than 25 ms between its
// samples is not compared). Throws InputError if the options
// are invalid, the trajectory has no stamps, or not one interval lies
// within the IMU's samples.
GyroCheckResult CheckRotationsAgainstGyro(const Trajectory& world_from_cam,
                                          const std::vector<ImuSample>& imu, const SensorRig& rig,
                                          const GyroCheckOptions& options);

// "rotations against the gyro: ..." lines for the console; the intervals
// with the largest errors listed (at most `num_worst`), their stamps in
// seconds since the trajectory's first.
std::string FormatGyroCheck(const GyroCheckResult& result, size_t num_worst = 5);

}  // namespace viosfm

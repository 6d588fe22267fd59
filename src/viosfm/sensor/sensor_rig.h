// The camera-IMU setup a dataset provides: intrinsics, extrinsics, IMU noise
// and timing. The body frame is the IMU frame (as in EuRoC).
#pragma once

#include <string>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct SensorRig {
  Camera camera;
  // Camera pose in the body (IMU) frame: x_body = body_from_cam * x_cam.
  Rigid3d body_from_cam;
  ImuNoise imu_noise;
  double camera_rate_hz = 20.0;  // camera frame rate, Hz
  // Time offset between the clocks: t_imu = t_cam + cam_time_offset_ns.
  timestamp_ns_t cam_time_offset_ns = 0;

  Rigid3d cam_from_body() const { return body_from_cam.Inverse(); }
  // A camera timestamp on the IMU clock.
  timestamp_ns_t CamToImuTime(timestamp_ns_t cam_time_ns) const {
    return cam_time_ns + cam_time_offset_ns;
  }

  // Empty if valid; otherwise names the bad field and why: an unsupported
  // camera model or wrong parameter count, non-positive image size or focal
  // length, non-finite values, a rotation quaternion whose norm differs from 1
  // by more than kQuaternionNormTolerance, invalid IMU noise, a non-positive
  // camera rate.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }

  static constexpr double kQuaternionNormTolerance = 1e-6;
};

}  // namespace viosfm

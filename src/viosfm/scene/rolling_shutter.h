// A rolling-shutter camera reads its rows out one after the other: row y
// (0 at the top) of a frame of `height` rows stamped t is exposed at
//   t + RowTimeOffset(y) = t + ((y + 0.5) / height - 0.5) * readout_s,
// so the stamp is the exposure time of the middle row (the simulator's
// convention, sim/robustness.h). The VIO corrects its own tracks
// (vio/rolling_shutter.h); the structure-from-motion stages model a global
// shutter at the stamp, so the keypoints they read are moved to where the
// camera would have seen them at the stamp, by the camera's rotation over
// their row's time offset (the gyro's): a camera turning at 1 rad/s with a
// readout of 20 ms is 10 mrad (9 px at a 900 px focal length) off at the top
// and bottom rows. The translation's share (the camera's velocity over the
// point's depth: 0.5 m/s at 2 m is 2.5 mrad at the top row) is left.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "viosfm/scene/features.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// s, time of row `row` of `height` rows relative to the frame's stamp.
double RowTimeOffset(double row, int height, double readout_s);

// The camera's angular velocity at camera time cam_ns, in the camera frame
// (rad/s): the mean gyro rate of the IMU samples within 10 ms of it (on the
// IMU's clock, rig.cam_time_offset_ns), the nearest sample if none; the
// bias is not removed (a bias of 0.01 rad/s moves a keypoint by under 0.1
// pixel over a readout's half). Zero without samples.
Eigen::Vector3d CamAngularRate(const SensorRig& rig, const std::vector<ImuSample>& imu,
                               timestamp_ns_t cam_ns);

// The bearing (x/z, y/z) a point seen at `normalized` offset_s after the
// stamp would have had at the stamp, for a camera turning at
// cam_angular_rate (its own frame): b(t) = Exp(w dt) b(t + dt). Unchanged
// when the rotated bearing leaves the front of the camera.
Eigen::Vector2d RotateBearingToStamp(const Eigen::Vector2d& normalized,
                                     const Eigen::Vector3d& cam_angular_rate, double offset_s);

// What the structure-from-motion stages need to compensate a sequence's
// frames: the readout and each frame's camera angular rate (CamAngularRate).
struct FrameRollingShutter {
  double readout_s = 0.0;                         // 0: a global shutter, nothing compensated
  std::vector<Eigen::Vector3d> cam_angular_rate;  // per image of the sequence
  bool active() const { return readout_s > 0.0 && !cam_angular_rate.empty(); }
};

// Moves each keypoint (pixels, of an image of `camera`) to where the
// camera, turning at cam_angular_rate, would have seen it at the frame's
// stamp; the keypoints' shapes are kept. Nothing changes when readout_s is 0.
void CompensateRollingShutterRotation(const Camera& camera, double readout_s,
                                      const Eigen::Vector3d& cam_angular_rate,
                                      FeatureKeypoints* keypoints);

}  // namespace viosfm

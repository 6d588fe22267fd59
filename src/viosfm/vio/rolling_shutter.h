// Rolling-shutter compensation of the VIO's observations. A rolling-shutter
// camera reads its rows out one after the other: row y (0 at the top) of a
// frame of `height` rows stamped t is exposed at
//   t + RowTimeOffset(y) = t + ((y + 0.5) / height - 0.5) * readout_s,
// so the stamp is the exposure time of the middle of the image (the
// simulator's convention, sim/robustness.h). The back end models a global
// shutter at the stamp, so each observation is moved to where the camera
// would have seen it at the stamp:
//  - a corner tracked from the previous frame moves with its image
//    velocity, measured between the two observations at their own row
//    times: n(t) = n - v * RowTimeOffset(y) (the correction of VINS-Mono's
//    rolling-shutter mode, with the readout known instead of estimated);
//    this follows both the rotation and the translation;
//  - a new corner, with no velocity yet, is rotated by the gyro's rotation
//    over its row's time offset (the translation's share is left).
// Only FeatureObservation::normalized changes; `pixel` stays where the
// corner was found.
#pragma once

#include <Eigen/Core>

#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/vio/frame_features.h"

namespace viosfm {

// Corrects `current` in place (see above). `previous` holds the previous
// frame's observations as the tracker gave them (uncorrected), or is null;
// `cam_angular_rate` is the camera's angular velocity at the frame, in the
// camera frame (rad/s; the gyro rate without its bias, rotated into the
// camera). Nothing changes when readout_s is 0.
void CorrectRollingShutter(const FrameFeatures* previous, double readout_s, int height,
                           const Eigen::Vector3d& cam_angular_rate, FrameFeatures* current);

}  // namespace viosfm

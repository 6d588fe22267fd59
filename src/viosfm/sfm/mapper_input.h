// The input of the batched mapper (batched_mapper.h): frames with their
// keypoints and VIO poses, and the verified matches of image pairs.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/vio_uncertainty.h"
#include "viosfm/sensor/camera.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/sfm/tracks.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/util/types.h"

namespace viosfm {

// One input frame.
struct MapperImage {
  image_t image_id = kInvalidImageId;
  camera_t camera_id = kInvalidCameraId;
  std::string name;  // as in the database (relative path)
  timestamp_ns_t timestamp_ns = 0;
  // Keypoints in raw (distorted) pixels, viosfm's convention.
  FeatureKeypoints keypoints;
  // The VIO pose of this frame's camera, in the world frame of its VIO
  // segment; none when the VIO gave no pose for this frame (not yet
  // initialised, lost, re-initialising): the frame is then registered from
  // the images, if they allow.
  std::optional<Rigid3d> vio_cam_from_world;
  // Segment, distance and rotation travelled of the VIO pose (default:
  // segment 0 at the origin; the uncertainty model then sees no travel).
  VioOdometer vio_odometer;
};

struct BatchedMapperInput {
  std::vector<Camera> cameras;
  // Frames in strictly increasing time order.
  std::vector<MapperImage> images;
  // Inlier matches of every accepted pair (point2D_idx index the images'
  // keypoints).
  std::vector<ImagePairMatches> verified_pairs;
  // The IMU's samples (increasing time) and the rig (camera-IMU rotation,
  // clock offset, IMU noise), for the gyro's priors in the final bundle
  // adjustment; empty: none.
  std::vector<ImuSample> imu;
  SensorRig rig;
  // s, the camera's rolling-shutter readout when the images' keypoints were
  // compensated for the camera's rotation during it (scene/rolling_shutter.h);
  // the mapper then compensates them for its motion too (batched_mapper.h).
  // 0: a global shutter.
  double rolling_shutter_readout_s = 0.0;
};

}  // namespace viosfm

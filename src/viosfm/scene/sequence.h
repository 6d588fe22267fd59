// An image sequence in memory, as the dataset readers (euroc.h,
// image_folder.h) return it: image stamps and paths, the camera, the
// camera-IMU extrinsics, the IMU stream and, when the dataset has it, the
// ground-truth state. Image pixels are not loaded here.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/scene/trajectory.h"
#include "viosfm/sensor/imu.h"
#include "viosfm/sensor/sensor_rig.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// One row of a ground-truth state file (EuRoC state_groundtruth_estimate0).
struct GroundTruthState {
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d world_from_body;
  Eigen::Vector3d velocity_in_world = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();          // rad/s
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();         // m/s^2
  // False if the row had only stamp, position and orientation; velocity and
  // biases are then zero.
  bool has_velocity_and_biases = false;
};

struct SequenceImage {
  timestamp_ns_t timestamp_ns = 0;
  std::filesystem::path path;  // the image file (absolute or relative to the working dir)
};

struct Sequence {
  // The dataset folder as given to the reader.
  std::filesystem::path root;
  // Ordered by strictly increasing timestamp.
  std::vector<SequenceImage> images;
  // Camera (camera_id 1), body_from_cam (identity without IMU), nominal
  // camera rate (0 if unknown) and IMU noise model (ImuNoise's defaults
  // without IMU).
  SensorRig rig;
  // Ordered by strictly increasing timestamp; empty without IMU.
  std::vector<ImuSample> imu;
  // Ordered by strictly increasing timestamp; empty without ground truth.
  std::vector<GroundTruthState> ground_truth;
  // The images are an unordered photo collection: their stamps only number
  // them (io/image_folder.h).
  bool unordered = false;
  // The camera was guessed from the image size, not calibrated: the bundle
  // adjustment refines its focal length and distortion.
  bool camera_guessed = false;

  bool has_imu() const { return !imu.empty(); }
  bool has_ground_truth() const { return !ground_truth.empty(); }
  size_t num_images() const { return images.size(); }
};

// The name of an image in a COLMAP database and model: its file name.
std::string DatabaseImageName(const SequenceImage& image);

// Frame rate from the median interval between consecutive images; 0 with
// fewer than two images.
double EstimateFrameRateHz(const std::vector<SequenceImage>& images);

// How the IMU covers the images' time span. With IMU and images only.
struct ImuCoverage {
  bool overlaps = false;  // some IMU sample lies within the images' span
  bool complete = false;  // the samples span every image
  // "images span [a, b] ns, IMU samples span [c, d] ns", for messages.
  std::string spans;
};
ImuCoverage CheckImuCoverage(const Sequence& sequence);

// The ground truth as world_from_body poses.
Trajectory GroundTruthBodyTrajectory(const Sequence& sequence);
// The ground truth as world_from_cam poses: world_from_body * body_from_cam.
Trajectory GroundTruthCameraTrajectory(const Sequence& sequence);

}  // namespace viosfm

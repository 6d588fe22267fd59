// A visual-inertial recording in a bag read as a Sequence, and a Sequence
// written as a bag (`viosfm convert`). The bag is a ROS 1 bag (rosbag.h) or a
// ROS 2 bag (rosbag2.h: sqlite3 .db3 or MCAP .mcap files, alone or in a
// folder with metadata.yaml), told by its content (bag_container.h); the
// messages are ROS 1's or CDR (ros_messages.h), the same fields either way.
//
// Reading
//   images   sensor_msgs/Image (mono8 or 8UC1; bgr8, rgb8, bgra8, rgba8
//            converted to grey) or sensor_msgs/CompressedImage (any format
//            OpenCV decodes: jpeg, png), stamped by header.stamp. Each image
//            is written to <extract_folder>/mav0/cam0/data/<stamp ns>.png (the
//            EuRoC layout, so the names are the ones a EuRoC folder of the same
//            recording has), because every stage of viosfm reads images from
//            files; a CompressedImage holding a JPEG or PNG file is written as
//            that file (<stamp ns>.jpg or .png), unchanged.
//   IMU      sensor_msgs/Imu: angular_velocity (rad/s), linear_acceleration
//            (m/s^2), header.stamp; orientation and covariances are ignored.
//   ground truth (optional)  geometry_msgs/PoseStamped or TransformStamped,
//            world_from_body; the topic /groundtruth/pose is read when present.
// (ROS 2 type names: sensor_msgs/msg/Image, ...; the early rosbag2 names
// without "/msg/" too.)
// Topics: given, or found by type when the bag has one topic of that type;
// with several, the EuRoC names /cam0/image_raw and /imu0 are taken when
// present. A ROS 2 topic must be serialized as CDR. Stamps are sorted; two
// messages with the same stamp are an error.
//
// Calibration (camera intrinsics, body_from_cam, IMU noise), the first that
// applies:
//   1. `rig`, given in code. This is the hook for calibration files viosfm
//      reads elsewhere (a Kalibr camchain.yaml + imu.yaml reader fills a
//      SensorRig and passes it here);
//   2. `camera_yaml` (+ `imu_yaml`): EuRoC/Kalibr sensor.yaml files (euroc.h);
//   3. the calibration `viosfm convert` embeds in the bags it writes: the
//      EuRoC sensor.yaml texts as std_msgs/String on /viosfm/cam0/sensor_yaml
//      and /viosfm/imu0/sensor_yaml (written to the extract folder as
//      mav0/cam0/sensor.yaml, mav0/imu0/sensor.yaml and read from there);
//   4. a EuRoC folder beside the bag: <bag folder>/mav0/cam0/sensor.yaml and
//      mav0/imu0/sensor.yaml (EuRoC ships V1_01_easy.bag next to the zip of
//      the same sequence).
// Without an IMU calibration (2 without imu_yaml, 4 without imu0/) the IMU
// noise keeps ImuNoise's defaults, with a warning.
//
// Errors (InputError naming the bag, the message's place (a byte offset, or
// a .db3's file and row) and the topic): not a bag, a truncated or corrupt
// record or CRC, a missing topic (the message lists the bag's topics), a
// topic of the wrong type, ROS 1 message MD5 or ROS 2 serialization, an
// unsupported image encoding, an image whose size differs from the
// calibration, duplicate stamps, no calibration.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "viosfm/io/bag_container.h"
#include "viosfm/io/rosbag.h"
#include "viosfm/scene/sequence.h"

namespace viosfm {

// The topics `viosfm convert` writes and EuRoC's bags use.
inline constexpr char kEurocImageTopic[] = "/cam0/image_raw";
inline constexpr char kEurocImuTopic[] = "/imu0";
inline constexpr char kGroundTruthTopic[] = "/groundtruth/pose";
inline constexpr char kCameraCalibrationTopic[] = "/viosfm/cam0/sensor_yaml";
inline constexpr char kImuCalibrationTopic[] = "/viosfm/imu0/sensor_yaml";

struct RosbagDatasetOptions {
  // Image topic; empty: found by type (see above). Default empty.
  std::string image_topic;
  // IMU topic; empty: found by type. Default empty.
  std::string imu_topic;
  // Ground-truth topic; empty: /groundtruth/pose when present. Default empty.
  std::string groundtruth_topic;
  // Calibration given in code (see above, 1). Default none.
  std::optional<SensorRig> rig;
  // EuRoC/Kalibr camera and IMU sensor.yaml (see above, 2). Default none.
  std::filesystem::path camera_yaml;
  std::filesystem::path imu_yaml;
  // Where the images (and an embedded calibration) are written, in the EuRoC
  // layout. Required.
  std::filesystem::path extract_folder;
  // A bag without an IMU topic is an error (true) or gives a sequence
  // without IMU (false). Default false.
  bool require_imu = false;

  // Empty if valid; otherwise names the bad field.
  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// "topic (type, N messages)" lines of a bag, for messages and `viosfm convert`.
std::string DescribeBagTopics(const BagReader& reader);

Sequence ReadRosbagDataset(const std::filesystem::path& bag, const RosbagDatasetOptions& options);

struct RosbagWriteOptions {
  std::string image_topic = kEurocImageTopic;
  std::string imu_topic = kEurocImuTopic;
  std::string groundtruth_topic = kGroundTruthTopic;
  // sensor_msgs/CompressedImage holding each image file's bytes unchanged
  // (format "png" or "jpeg" from the extension) instead of
  // sensor_msgs/Image mono8 (EuRoC's). Default false.
  bool compressed_images = false;
  // Embed the calibration as sensor.yaml texts (see above, 3). Default true.
  bool embed_calibration = true;
  // The sensor.yaml texts to embed as they are, instead of texts written
  // from the sequence's rig: a EuRoC folder's own files, so that the bag
  // gives the folder's rig bit for bit (a rotation written as text and read
  // again can change in its last bit). Empty: written from the rig. See
  // UseEurocCalibrationTexts. Default empty.
  std::string camera_yaml_text;
  std::string imu_yaml_text;
  // The container (by the bag's extension) and its compression.
  BagWriterOptions writer;

  std::string Validate() const;
  bool Check() const { return Validate().empty(); }
};

// Writes the sequence's images (read from their files), IMU samples, ground
// truth (world_from_body only: velocities and biases are not carried) and
// calibration, in time order, as the container `bag`'s extension names
// (".bag" ROS 1, ".db3" rosbag2 sqlite3, ".mcap" MCAP); every message's
// record time is its stamp.
void WriteRosbagDataset(const Sequence& sequence, const std::filesystem::path& bag,
                        const RosbagWriteOptions& options = {});

// Sets options->camera_yaml_text and imu_yaml_text to the sensor.yaml files
// of the EuRoC folder `folder` (holding mav0/, or mav0/ itself), the
// sequence written being that folder's. Leaves them empty when a file is
// missing or the IMU's T_BS is not the identity: the folder's reader has
// then re-expressed the ground truth in the IMU frame, and reading the bag
// with the original texts would do it a second time.
void UseEurocCalibrationTexts(const std::filesystem::path& folder, RosbagWriteOptions* options);

}  // namespace viosfm

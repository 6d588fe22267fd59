// The ROS messages viosfm reads from and writes to bags: ROS 1's (rosbag.h)
// and ROS 2's (rosbag2.h, mcap.h).
//
// ROS 1's serialization: little-endian; a string or a variable-length array
// is a uint32 length then its bytes or elements; fixed arrays have no length;
// time is uint32 seconds, uint32 nanoseconds; nested messages are inlined.
//
//   sensor_msgs/Image            header, height, width, encoding, is_bigendian, step, data
//   sensor_msgs/CompressedImage  header, format ("jpeg", "png",
//                                "mono8; jpeg compressed mono8"), data
//   sensor_msgs/Imu              header, orientation, orientation_covariance[9],
//                                angular_velocity, .._covariance[9],
//                                linear_acceleration, .._covariance[9]
//   geometry_msgs/PoseStamped    header, pose (position, orientation x y z w)
//   geometry_msgs/TransformStamped  header, child_frame_id, transform (translation, rotation)
//   std_msgs/String              data
// (std_msgs/Header: seq, stamp, frame_id.)
//
// The MD5 sums are ROS's (as Debian's libsensor-msgs-dev, libgeometry-msgs-dev
// and libstd-msgs-dev headers state them); the definitions are the .msg
// texts without comments, which is what tools that decode a bag without the
// message packages (rosbag's Python reader, rosbags, Foxglove) need.
//
// ROS 2's serialization is CDR (cdr.h); its types are named
// "sensor_msgs/msg/Image" (rosbag2 before 2020: "sensor_msgs/Image"), its
// std_msgs/Header is (builtin_interfaces/Time stamp: int32 sec, uint32
// nanosec; string frame_id), without seq; the other fields are ROS 1's. The
// definitions are the ros2msg texts (the .msg files without comments, the
// types they use appended after "====...\nMSG: pkg/Type" lines), which MCAP
// schemas and rosbag2's message_definitions table hold.
//
// Deserialize* throw InputError("<where>: <what>") when the bytes do not hold
// the message (too short, a length past the end, bytes left over).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct RosMessageType {
  const char* name;    // "sensor_msgs/Image" (ROS 1), "sensor_msgs/msg/Image" (ROS 2)
  const char* md5sum;  // ROS 1 only ("" for ROS 2)
  const char* definition;
};

extern const RosMessageType kRosImageType;
extern const RosMessageType kRosCompressedImageType;
extern const RosMessageType kRosImuType;
extern const RosMessageType kRosPoseStampedType;
extern const RosMessageType kRosTransformStampedType;
extern const RosMessageType kRosStringType;

extern const RosMessageType kRos2ImageType;
extern const RosMessageType kRos2CompressedImageType;
extern const RosMessageType kRos2ImuType;
extern const RosMessageType kRos2PoseStampedType;
extern const RosMessageType kRos2TransformStampedType;
extern const RosMessageType kRos2StringType;

// A ROS 2 type name in its current form: "sensor_msgs/msg/Image" for
// "sensor_msgs/Image" or "sensor_msgs/msg/Image"; other names unchanged.
std::string NormalizeRos2TypeName(const std::string& type);

struct RosHeader {
  uint32_t seq = 0;  // ROS 1 only
  timestamp_ns_t stamp_ns = 0;
  std::string frame_id;
};

struct RosImage {
  RosHeader header;
  uint32_t height = 0;
  uint32_t width = 0;
  std::string encoding;  // "mono8", "bgr8", "rgb8", ...
  uint8_t is_bigendian = 0;
  uint32_t step = 0;  // bytes per row
  std::vector<uint8_t> data;
};

struct RosCompressedImage {
  RosHeader header;
  std::string format;
  std::vector<uint8_t> data;
};

struct RosImu {
  RosHeader header;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d orientation_covariance = Eigen::Matrix3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // rad/s
  Eigen::Matrix3d angular_velocity_covariance = Eigen::Matrix3d::Zero();
  Eigen::Vector3d linear_acceleration = Eigen::Vector3d::Zero();  // m/s^2
  Eigen::Matrix3d linear_acceleration_covariance = Eigen::Matrix3d::Zero();
};

struct RosPoseStamped {
  RosHeader header;
  Rigid3d pose;  // the pose of the child frame in header.frame_id
};

struct RosTransformStamped {
  RosHeader header;
  std::string child_frame_id;
  Rigid3d transform;  // header.frame_id_from_child_frame_id
};

std::vector<uint8_t> SerializeRosImage(const RosImage& message);
std::vector<uint8_t> SerializeRosCompressedImage(const RosCompressedImage& message);
std::vector<uint8_t> SerializeRosImu(const RosImu& message);
std::vector<uint8_t> SerializeRosPoseStamped(const RosPoseStamped& message);
std::vector<uint8_t> SerializeRosTransformStamped(const RosTransformStamped& message);
std::vector<uint8_t> SerializeRosString(const std::string& message);

// `where` prefixes error messages (e.g. "rec.bag: byte offset 5012 (/cam0/image_raw)").
RosImage DeserializeRosImage(std::span<const uint8_t> bytes, const std::string& where);
RosCompressedImage DeserializeRosCompressedImage(std::span<const uint8_t> bytes,
                                                 const std::string& where);
RosImu DeserializeRosImu(std::span<const uint8_t> bytes, const std::string& where);
RosPoseStamped DeserializeRosPoseStamped(std::span<const uint8_t> bytes, const std::string& where);
RosTransformStamped DeserializeRosTransformStamped(std::span<const uint8_t> bytes,
                                                   const std::string& where);
std::string DeserializeRosString(std::span<const uint8_t> bytes, const std::string& where);

// ROS 2 (CDR). Serialize* write little-endian CDR; Deserialize* read either
// byte order. header.seq is not part of a ROS 2 message (read as 0).
std::vector<uint8_t> SerializeCdrImage(const RosImage& message);
std::vector<uint8_t> SerializeCdrCompressedImage(const RosCompressedImage& message);
std::vector<uint8_t> SerializeCdrImu(const RosImu& message);
std::vector<uint8_t> SerializeCdrPoseStamped(const RosPoseStamped& message);
std::vector<uint8_t> SerializeCdrTransformStamped(const RosTransformStamped& message);
std::vector<uint8_t> SerializeCdrString(const std::string& message);

RosImage DeserializeCdrImage(std::span<const uint8_t> bytes, const std::string& where);
RosCompressedImage DeserializeCdrCompressedImage(std::span<const uint8_t> bytes,
                                                 const std::string& where);
RosImu DeserializeCdrImu(std::span<const uint8_t> bytes, const std::string& where);
RosPoseStamped DeserializeCdrPoseStamped(std::span<const uint8_t> bytes, const std::string& where);
RosTransformStamped DeserializeCdrTransformStamped(std::span<const uint8_t> bytes,
                                                   const std::string& where);
std::string DeserializeCdrString(std::span<const uint8_t> bytes, const std::string& where);

}  // namespace viosfm

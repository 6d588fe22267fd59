#include "viosfm/io/ros_messages.h"

#include <bit>
#include <cstring>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr char kHeaderDefinition[] =
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n";
constexpr char kQuaternionDefinition[] =
    "================================================================================\n"
    "MSG: geometry_msgs/Quaternion\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n"
    "float64 w\n";
constexpr char kVector3Definition[] =
    "================================================================================\n"
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

const std::string kImageDefinition = std::string(
                                         "Header header\n"
                                         "uint32 height\n"
                                         "uint32 width\n"
                                         "string encoding\n"
                                         "uint8 is_bigendian\n"
                                         "uint32 step\n"
                                         "uint8[] data\n") +
                                     kHeaderDefinition;
const std::string kCompressedImageDefinition = std::string(
                                                   "Header header\n"
                                                   "string format\n"
                                                   "uint8[] data\n") +
                                               kHeaderDefinition;
const std::string kImuDefinition = std::string(
                                       "Header header\n"
                                       "geometry_msgs/Quaternion orientation\n"
                                       "float64[9] orientation_covariance\n"
                                       "geometry_msgs/Vector3 angular_velocity\n"
                                       "float64[9] angular_velocity_covariance\n"
                                       "geometry_msgs/Vector3 linear_acceleration\n"
                                       "float64[9] linear_acceleration_covariance\n") +
                                   kHeaderDefinition + kQuaternionDefinition + kVector3Definition;
const std::string kPoseStampedDefinition =
    std::string(
        "Header header\n"
        "geometry_msgs/Pose pose\n") +
    kHeaderDefinition +
    "================================================================================\n"
    "MSG: geometry_msgs/Pose\n"
    "geometry_msgs/Point position\n"
    "geometry_msgs/Quaternion orientation\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Point\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n" +
    kQuaternionDefinition;
const std::string kTransformStampedDefinition =
    std::string(
        "Header header\n"
        "string child_frame_id\n"
        "geometry_msgs/Transform transform\n") +
    kHeaderDefinition +
    "================================================================================\n"
    "MSG: geometry_msgs/Transform\n"
    "geometry_msgs/Vector3 translation\n"
    "geometry_msgs/Quaternion rotation\n" +
    kVector3Definition + kQuaternionDefinition;

// Appends values in ROS 1 serialization.
class Writer {
 public:
  template <typename T>
  void Put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    uint64_t bits = 0;
    if constexpr (std::is_same_v<T, double>) {
      bits = std::bit_cast<uint64_t>(value);
    } else {
      bits = static_cast<uint64_t>(value);
    }
    for (size_t i = 0; i < sizeof(T); ++i) bytes_.push_back(static_cast<uint8_t>(bits >> (8 * i)));
  }
  void PutBytes(const uint8_t* data, size_t size) {
    VIOSFM_CHECK_LE(size, 0xffffffffu) << "ROS array too long";
    Put<uint32_t>(static_cast<uint32_t>(size));
    bytes_.insert(bytes_.end(), data, data + size);
  }
  void PutString(const std::string& text) {
    PutBytes(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  }
  void PutTime(timestamp_ns_t time_ns) {
    VIOSFM_CHECK(time_ns >= 0 && time_ns / 1'000'000'000 <= 0xffffffffLL)
        << "time " << time_ns << " ns is outside ROS time";
    Put<uint32_t>(static_cast<uint32_t>(time_ns / 1'000'000'000));
    Put<uint32_t>(static_cast<uint32_t>(time_ns % 1'000'000'000));
  }
  void PutHeader(const RosHeader& header) {
    Put<uint32_t>(header.seq);
    PutTime(header.stamp_ns);
    PutString(header.frame_id);
  }
  void PutVector3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) Put<double>(v[i]);
  }
  void PutQuaternion(const Eigen::Quaterniond& q) {
    Put<double>(q.x());
    Put<double>(q.y());
    Put<double>(q.z());
    Put<double>(q.w());
  }
  void PutCovariance(const Eigen::Matrix3d& m) {  // float64[9], row-major
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) Put<double>(m(r, c));
    }
  }
  std::vector<uint8_t> Take() { return std::move(bytes_); }

 private:
  std::vector<uint8_t> bytes_;
};

// Reads values in ROS 1 serialization; every overrun is an InputError.
class Reader {
 public:
  Reader(std::span<const uint8_t> bytes, const std::string& where, const char* type)
      : bytes_(bytes), where_(where), type_(type) {}

  template <typename T>
  T Get(const char* field) {
    Require(sizeof(T), field);
    uint64_t bits = 0;
    for (size_t i = 0; i < sizeof(T); ++i) bits |= uint64_t{bytes_[offset_ + i]} << (8 * i);
    offset_ += sizeof(T);
    if constexpr (std::is_same_v<T, double>) {
      return std::bit_cast<double>(bits);
    } else {
      return static_cast<T>(bits);
    }
  }
  std::span<const uint8_t> GetBytes(const char* field) {
    const uint32_t size = Get<uint32_t>(field);
    Require(size, field);
    const std::span<const uint8_t> out = bytes_.subspan(offset_, size);
    offset_ += size;
    return out;
  }
  std::string GetString(const char* field) {
    const std::span<const uint8_t> bytes = GetBytes(field);
    return std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  std::vector<uint8_t> GetByteVector(const char* field) {
    const std::span<const uint8_t> bytes = GetBytes(field);
    return std::vector<uint8_t>(bytes.begin(), bytes.end());
  }
  timestamp_ns_t GetTime(const char* field) {
    const uint32_t sec = Get<uint32_t>(field);
    const uint32_t nsec = Get<uint32_t>(field);
    if (nsec >= 1'000'000'000u) {
      Fail(std::string(field) + " has " + std::to_string(nsec) + " nanoseconds (expected < 1e9)");
    }
    return static_cast<timestamp_ns_t>(sec) * 1'000'000'000 + nsec;
  }
  RosHeader GetHeader() {
    RosHeader header;
    header.seq = Get<uint32_t>("header.seq");
    header.stamp_ns = GetTime("header.stamp");
    header.frame_id = GetString("header.frame_id");
    return header;
  }
  Eigen::Vector3d GetVector3(const char* field) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = Get<double>(field);
    return v;
  }
  Eigen::Quaterniond GetQuaternion(const char* field) {
    const double x = Get<double>(field);
    const double y = Get<double>(field);
    const double z = Get<double>(field);
    const double w = Get<double>(field);
    return Eigen::Quaterniond(w, x, y, z);
  }
  Eigen::Matrix3d GetCovariance(const char* field) {
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m(r, c) = Get<double>(field);
    }
    return m;
  }
  void ExpectEnd() {
    if (offset_ != bytes_.size()) {
      Fail(std::to_string(bytes_.size() - offset_) + " bytes left after the message (" +
           std::to_string(bytes_.size()) + " bytes in all): not a " + type_ + "?");
    }
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(where_ + ": " + type_ + ": " + what);
  }

 private:
  void Require(uint64_t size, const char* field) {
    if (size > bytes_.size() - offset_) {
      Fail(std::string(field) + " needs " + std::to_string(size) + " bytes at message offset " +
           std::to_string(offset_) + ", only " + std::to_string(bytes_.size() - offset_) +
           " left (the message has " + std::to_string(bytes_.size()) + " bytes)");
    }
  }

  std::span<const uint8_t> bytes_;
  size_t offset_ = 0;
  const std::string& where_;
  const char* type_;
};

}  // namespace

const RosMessageType kRosImageType = {"sensor_msgs/Image", "060021388200f6f0f447d0fcd9c64743",
                                      kImageDefinition.c_str()};
const RosMessageType kRosCompressedImageType = {"sensor_msgs/CompressedImage",
                                                "8f7a12909da2c9d3332d540a0977563f",
                                                kCompressedImageDefinition.c_str()};
const RosMessageType kRosImuType = {"sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2",
                                    kImuDefinition.c_str()};
const RosMessageType kRosPoseStampedType = {"geometry_msgs/PoseStamped",
                                            "d3812c3cbc69362b77dc0b19b345f8f5",
                                            kPoseStampedDefinition.c_str()};
const RosMessageType kRosTransformStampedType = {"geometry_msgs/TransformStamped",
                                                 "b5764a33bfeb3588febc2682852579b0",
                                                 kTransformStampedDefinition.c_str()};
const RosMessageType kRosStringType = {"std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1",
                                       "string data\n"};

std::vector<uint8_t> SerializeRosImage(const RosImage& message) {
  Writer writer;
  writer.PutHeader(message.header);
  writer.Put<uint32_t>(message.height);
  writer.Put<uint32_t>(message.width);
  writer.PutString(message.encoding);
  writer.Put<uint8_t>(message.is_bigendian);
  writer.Put<uint32_t>(message.step);
  writer.PutBytes(message.data.data(), message.data.size());
  return writer.Take();
}

std::vector<uint8_t> SerializeRosCompressedImage(const RosCompressedImage& message) {
  Writer writer;
  writer.PutHeader(message.header);
  writer.PutString(message.format);
  writer.PutBytes(message.data.data(), message.data.size());
  return writer.Take();
}

std::vector<uint8_t> SerializeRosImu(const RosImu& message) {
  Writer writer;
  writer.PutHeader(message.header);
  writer.PutQuaternion(message.orientation);
  writer.PutCovariance(message.orientation_covariance);
  writer.PutVector3(message.angular_velocity);
  writer.PutCovariance(message.angular_velocity_covariance);
  writer.PutVector3(message.linear_acceleration);
  writer.PutCovariance(message.linear_acceleration_covariance);
  return writer.Take();
}

std::vector<uint8_t> SerializeRosPoseStamped(const RosPoseStamped& message) {
  Writer writer;
  writer.PutHeader(message.header);
  writer.PutVector3(message.pose.translation);
  writer.PutQuaternion(message.pose.rotation);
  return writer.Take();
}

std::vector<uint8_t> SerializeRosTransformStamped(const RosTransformStamped& message) {
  Writer writer;
  writer.PutHeader(message.header);
  writer.PutString(message.child_frame_id);
  writer.PutVector3(message.transform.translation);
  writer.PutQuaternion(message.transform.rotation);
  return writer.Take();
}

std::vector<uint8_t> SerializeRosString(const std::string& message) {
  Writer writer;
  writer.PutString(message);
  return writer.Take();
}

RosImage DeserializeRosImage(std::span<const uint8_t> bytes, const std::string& where) {
  Reader reader(bytes, where, kRosImageType.name);
  RosImage message;
  message.header = reader.GetHeader();
  message.height = reader.Get<uint32_t>("height");
  message.width = reader.Get<uint32_t>("width");
  message.encoding = reader.GetString("encoding");
  message.is_bigendian = reader.Get<uint8_t>("is_bigendian");
  message.step = reader.Get<uint32_t>("step");
  message.data = reader.GetByteVector("data");
  reader.ExpectEnd();
  return message;
}

RosCompressedImage DeserializeRosCompressedImage(std::span<const uint8_t> bytes,
                                                 const std::string& where) {
  Reader reader(bytes, where, kRosCompressedImageType.name);
  RosCompressedImage message;
  message.header = reader.GetHeader();
  message.format = reader.GetString("format");
  message.data = reader.GetByteVector("data");
  reader.ExpectEnd();
  return message;
}

RosImu DeserializeRosImu(std::span<const uint8_t> bytes, const std::string& where) {
  Reader reader(bytes, where, kRosImuType.name);
  RosImu message;
  message.header = reader.GetHeader();
  message.orientation = reader.GetQuaternion("orientation");
  message.orientation_covariance = reader.GetCovariance("orientation_covariance");
  message.angular_velocity = reader.GetVector3("angular_velocity");
  message.angular_velocity_covariance = reader.GetCovariance("angular_velocity_covariance");
  message.linear_acceleration = reader.GetVector3("linear_acceleration");
  message.linear_acceleration_covariance = reader.GetCovariance("linear_acceleration_covariance");
  reader.ExpectEnd();
  return message;
}

RosPoseStamped DeserializeRosPoseStamped(std::span<const uint8_t> bytes, const std::string& where) {
  Reader reader(bytes, where, kRosPoseStampedType.name);
  RosPoseStamped message;
  message.header = reader.GetHeader();
  message.pose.translation = reader.GetVector3("pose.position");
  message.pose.rotation = reader.GetQuaternion("pose.orientation");
  reader.ExpectEnd();
  return message;
}

RosTransformStamped DeserializeRosTransformStamped(std::span<const uint8_t> bytes,
                                                   const std::string& where) {
  Reader reader(bytes, where, kRosTransformStampedType.name);
  RosTransformStamped message;
  message.header = reader.GetHeader();
  message.child_frame_id = reader.GetString("child_frame_id");
  message.transform.translation = reader.GetVector3("transform.translation");
  message.transform.rotation = reader.GetQuaternion("transform.rotation");
  reader.ExpectEnd();
  return message;
}

std::string DeserializeRosString(std::span<const uint8_t> bytes, const std::string& where) {
  Reader reader(bytes, where, kRosStringType.name);
  std::string message = reader.GetString("data");
  reader.ExpectEnd();
  return message;
}

}  // namespace viosfm

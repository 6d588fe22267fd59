#include "viosfm/io/ros_messages.h"

#include <bit>
#include <cstring>

#include "viosfm/io/cdr.h"
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

// ROS 2 (ros2msg): the same texts with ROS 2's Header and type names.
constexpr char kRos2HeaderDefinition[] =
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n";
const std::string kRos2ImageDefinition = std::string(
                                             "std_msgs/Header header\n"
                                             "uint32 height\n"
                                             "uint32 width\n"
                                             "string encoding\n"
                                             "uint8 is_bigendian\n"
                                             "uint32 step\n"
                                             "uint8[] data\n") +
                                         kRos2HeaderDefinition;
const std::string kRos2CompressedImageDefinition = std::string(
                                                       "std_msgs/Header header\n"
                                                       "string format\n"
                                                       "uint8[] data\n") +
                                                   kRos2HeaderDefinition;
const std::string kRos2ImuDefinition = std::string(
                                           "std_msgs/Header header\n"
                                           "geometry_msgs/Quaternion orientation\n"
                                           "float64[9] orientation_covariance\n"
                                           "geometry_msgs/Vector3 angular_velocity\n"
                                           "float64[9] angular_velocity_covariance\n"
                                           "geometry_msgs/Vector3 linear_acceleration\n"
                                           "float64[9] linear_acceleration_covariance\n") +
                                       kRos2HeaderDefinition + kQuaternionDefinition +
                                       kVector3Definition;
const std::string kRos2PoseStampedDefinition =
    std::string(
        "std_msgs/Header header\n"
        "geometry_msgs/Pose pose\n") +
    kRos2HeaderDefinition +
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
const std::string kRos2TransformStampedDefinition =
    std::string(
        "std_msgs/Header header\n"
        "string child_frame_id\n"
        "geometry_msgs/Transform transform\n") +
    kRos2HeaderDefinition +
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
  void PutByteVector(const std::vector<uint8_t>& data) { PutBytes(data.data(), data.size()); }
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

// The fields ROS 2 messages share, in CDR.
class CdrMessageWriter {
 public:
  void PutHeader(const RosHeader& header) {
    VIOSFM_CHECK(header.stamp_ns >= 0 && header.stamp_ns / 1'000'000'000 <= 0x7fffffffLL)
        << "stamp " << header.stamp_ns << " ns is outside ROS 2 time (int32 seconds)";
    writer.Put<int32_t>(static_cast<int32_t>(header.stamp_ns / 1'000'000'000));
    writer.Put<uint32_t>(static_cast<uint32_t>(header.stamp_ns % 1'000'000'000));
    writer.PutString(header.frame_id);
  }
  void PutVector3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) writer.Put<double>(v[i]);
  }
  void PutQuaternion(const Eigen::Quaterniond& q) {
    writer.Put<double>(q.x());
    writer.Put<double>(q.y());
    writer.Put<double>(q.z());
    writer.Put<double>(q.w());
  }
  void PutCovariance(const Eigen::Matrix3d& m) {  // float64[9], row-major
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) writer.Put<double>(m(r, c));
    }
  }
  template <typename T>
  void Put(T value) {
    writer.Put<T>(value);
  }
  void PutString(const std::string& text) { writer.PutString(text); }
  void PutByteVector(const std::vector<uint8_t>& data) { writer.PutByteSequence(data); }
  std::vector<uint8_t> Take() { return writer.Take(); }
  CdrWriter writer;
};

class CdrMessageReader {
 public:
  CdrMessageReader(std::span<const uint8_t> bytes, const std::string& where, const char* type)
      : reader(bytes, where, type) {}

  RosHeader GetHeader() {
    RosHeader header;
    const int32_t sec = reader.Get<int32_t>("header.stamp.sec");
    const uint32_t nanosec = reader.Get<uint32_t>("header.stamp.nanosec");
    if (sec < 0) {
      reader.Fail("header.stamp.sec is " + std::to_string(sec) + " (before 1970: not a stamp)");
    }
    if (nanosec >= 1'000'000'000u) {
      reader.Fail("header.stamp.nanosec is " + std::to_string(nanosec) + " (expected < 1e9)");
    }
    header.stamp_ns = static_cast<timestamp_ns_t>(sec) * 1'000'000'000 + nanosec;
    header.frame_id = reader.GetString("header.frame_id");
    return header;
  }
  Eigen::Vector3d GetVector3(const char* field) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = reader.Get<double>(field);
    return v;
  }
  Eigen::Quaterniond GetQuaternion(const char* field) {
    const double x = reader.Get<double>(field);
    const double y = reader.Get<double>(field);
    const double z = reader.Get<double>(field);
    const double w = reader.Get<double>(field);
    return Eigen::Quaterniond(w, x, y, z);
  }
  Eigen::Matrix3d GetCovariance(const char* field) {
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m(r, c) = reader.Get<double>(field);
    }
    return m;
  }
  std::vector<uint8_t> GetByteVector(const char* field) {
    const std::span<const uint8_t> bytes = reader.GetByteSequence(field);
    return std::vector<uint8_t>(bytes.begin(), bytes.end());
  }
  template <typename T>
  T Get(const char* field) {
    return reader.Get<T>(field);
  }
  std::string GetString(const char* field) { return reader.GetString(field); }
  void ExpectEnd() { reader.ExpectEnd(); }
  CdrReader reader;
};

// The fields of the messages in their order, the same for ROS 1 and ROS 2:
// `Out` is Writer or CdrMessageWriter, `In` Reader or CdrMessageReader
// (each encodes the fields its own way).
template <class Out>
std::vector<uint8_t> WriteImage(const RosImage& message, Out out) {
  out.PutHeader(message.header);
  out.template Put<uint32_t>(message.height);
  out.template Put<uint32_t>(message.width);
  out.PutString(message.encoding);
  out.template Put<uint8_t>(message.is_bigendian);
  out.template Put<uint32_t>(message.step);
  out.PutByteVector(message.data);
  return out.Take();
}

template <class Out>
std::vector<uint8_t> WriteCompressedImage(const RosCompressedImage& message, Out out) {
  out.PutHeader(message.header);
  out.PutString(message.format);
  out.PutByteVector(message.data);
  return out.Take();
}

template <class Out>
std::vector<uint8_t> WriteImu(const RosImu& message, Out out) {
  out.PutHeader(message.header);
  out.PutQuaternion(message.orientation);
  out.PutCovariance(message.orientation_covariance);
  out.PutVector3(message.angular_velocity);
  out.PutCovariance(message.angular_velocity_covariance);
  out.PutVector3(message.linear_acceleration);
  out.PutCovariance(message.linear_acceleration_covariance);
  return out.Take();
}

template <class Out>
std::vector<uint8_t> WritePoseStamped(const RosPoseStamped& message, Out out) {
  out.PutHeader(message.header);
  out.PutVector3(message.pose.translation);
  out.PutQuaternion(message.pose.rotation);
  return out.Take();
}

template <class Out>
std::vector<uint8_t> WriteTransformStamped(const RosTransformStamped& message, Out out) {
  out.PutHeader(message.header);
  out.PutString(message.child_frame_id);
  out.PutVector3(message.transform.translation);
  out.PutQuaternion(message.transform.rotation);
  return out.Take();
}

template <class In>
RosImage ReadImage(In in) {
  RosImage message;
  message.header = in.GetHeader();
  message.height = in.template Get<uint32_t>("height");
  message.width = in.template Get<uint32_t>("width");
  message.encoding = in.GetString("encoding");
  message.is_bigendian = in.template Get<uint8_t>("is_bigendian");
  message.step = in.template Get<uint32_t>("step");
  message.data = in.GetByteVector("data");
  in.ExpectEnd();
  return message;
}

template <class In>
RosCompressedImage ReadCompressedImage(In in) {
  RosCompressedImage message;
  message.header = in.GetHeader();
  message.format = in.GetString("format");
  message.data = in.GetByteVector("data");
  in.ExpectEnd();
  return message;
}

template <class In>
RosImu ReadImu(In in) {
  RosImu message;
  message.header = in.GetHeader();
  message.orientation = in.GetQuaternion("orientation");
  message.orientation_covariance = in.GetCovariance("orientation_covariance");
  message.angular_velocity = in.GetVector3("angular_velocity");
  message.angular_velocity_covariance = in.GetCovariance("angular_velocity_covariance");
  message.linear_acceleration = in.GetVector3("linear_acceleration");
  message.linear_acceleration_covariance = in.GetCovariance("linear_acceleration_covariance");
  in.ExpectEnd();
  return message;
}

template <class In>
RosPoseStamped ReadPoseStamped(In in) {
  RosPoseStamped message;
  message.header = in.GetHeader();
  message.pose.translation = in.GetVector3("pose.position");
  message.pose.rotation = in.GetQuaternion("pose.orientation");
  in.ExpectEnd();
  return message;
}

template <class In>
RosTransformStamped ReadTransformStamped(In in) {
  RosTransformStamped message;
  message.header = in.GetHeader();
  message.child_frame_id = in.GetString("child_frame_id");
  message.transform.translation = in.GetVector3("transform.translation");
  message.transform.rotation = in.GetQuaternion("transform.rotation");
  in.ExpectEnd();
  return message;
}

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

const RosMessageType kRos2ImageType = {"sensor_msgs/msg/Image", "", kRos2ImageDefinition.c_str()};
const RosMessageType kRos2CompressedImageType = {"sensor_msgs/msg/CompressedImage", "",
                                                 kRos2CompressedImageDefinition.c_str()};
const RosMessageType kRos2ImuType = {"sensor_msgs/msg/Imu", "", kRos2ImuDefinition.c_str()};
const RosMessageType kRos2PoseStampedType = {"geometry_msgs/msg/PoseStamped", "",
                                             kRos2PoseStampedDefinition.c_str()};
const RosMessageType kRos2TransformStampedType = {"geometry_msgs/msg/TransformStamped", "",
                                                  kRos2TransformStampedDefinition.c_str()};
const RosMessageType kRos2StringType = {"std_msgs/msg/String", "", "string data\n"};

std::string NormalizeRos2TypeName(const std::string& type) {
  const size_t slash = type.find('/');
  if (slash == std::string::npos || type.find('/', slash + 1) != std::string::npos) return type;
  return type.substr(0, slash) + "/msg/" + type.substr(slash + 1);
}

std::vector<uint8_t> SerializeRosImage(const RosImage& message) {
  return WriteImage(message, Writer());
}

std::vector<uint8_t> SerializeRosCompressedImage(const RosCompressedImage& message) {
  return WriteCompressedImage(message, Writer());
}

std::vector<uint8_t> SerializeRosImu(const RosImu& message) {
  return WriteImu(message, Writer());
}

std::vector<uint8_t> SerializeRosPoseStamped(const RosPoseStamped& message) {
  return WritePoseStamped(message, Writer());
}

std::vector<uint8_t> SerializeRosTransformStamped(const RosTransformStamped& message) {
  return WriteTransformStamped(message, Writer());
}

std::vector<uint8_t> SerializeRosString(const std::string& message) {
  Writer writer;
  writer.PutString(message);
  return writer.Take();
}

RosImage DeserializeRosImage(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadImage(Reader(bytes, where, kRosImageType.name));
}

RosCompressedImage DeserializeRosCompressedImage(std::span<const uint8_t> bytes,
                                                 const std::string& where) {
  return ReadCompressedImage(Reader(bytes, where, kRosCompressedImageType.name));
}

RosImu DeserializeRosImu(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadImu(Reader(bytes, where, kRosImuType.name));
}

RosPoseStamped DeserializeRosPoseStamped(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadPoseStamped(Reader(bytes, where, kRosPoseStampedType.name));
}

RosTransformStamped DeserializeRosTransformStamped(std::span<const uint8_t> bytes,
                                                   const std::string& where) {
  return ReadTransformStamped(Reader(bytes, where, kRosTransformStampedType.name));
}

std::string DeserializeRosString(std::span<const uint8_t> bytes, const std::string& where) {
  Reader reader(bytes, where, kRosStringType.name);
  std::string message = reader.GetString("data");
  reader.ExpectEnd();
  return message;
}

// ----------------------------------------------------------------------------
// ROS 2 (CDR)

std::vector<uint8_t> SerializeCdrImage(const RosImage& message) {
  return WriteImage(message, CdrMessageWriter());
}

std::vector<uint8_t> SerializeCdrCompressedImage(const RosCompressedImage& message) {
  return WriteCompressedImage(message, CdrMessageWriter());
}

std::vector<uint8_t> SerializeCdrImu(const RosImu& message) {
  return WriteImu(message, CdrMessageWriter());
}

std::vector<uint8_t> SerializeCdrPoseStamped(const RosPoseStamped& message) {
  return WritePoseStamped(message, CdrMessageWriter());
}

std::vector<uint8_t> SerializeCdrTransformStamped(const RosTransformStamped& message) {
  return WriteTransformStamped(message, CdrMessageWriter());
}

std::vector<uint8_t> SerializeCdrString(const std::string& message) {
  CdrWriter writer;
  writer.PutString(message);
  return writer.Take();
}

RosImage DeserializeCdrImage(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadImage(CdrMessageReader(bytes, where, kRos2ImageType.name));
}

RosCompressedImage DeserializeCdrCompressedImage(std::span<const uint8_t> bytes,
                                                 const std::string& where) {
  return ReadCompressedImage(CdrMessageReader(bytes, where, kRos2CompressedImageType.name));
}

RosImu DeserializeCdrImu(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadImu(CdrMessageReader(bytes, where, kRos2ImuType.name));
}

RosPoseStamped DeserializeCdrPoseStamped(std::span<const uint8_t> bytes, const std::string& where) {
  return ReadPoseStamped(CdrMessageReader(bytes, where, kRos2PoseStampedType.name));
}

RosTransformStamped DeserializeCdrTransformStamped(std::span<const uint8_t> bytes,
                                                   const std::string& where) {
  return ReadTransformStamped(CdrMessageReader(bytes, where, kRos2TransformStampedType.name));
}

std::string DeserializeCdrString(std::span<const uint8_t> bytes, const std::string& where) {
  CdrReader reader(bytes, where, kRos2StringType.name);
  std::string message = reader.GetString("data");
  reader.ExpectEnd();
  return message;
}

}  // namespace viosfm

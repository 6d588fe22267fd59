#include "viosfm/io/rosbag_dataset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "viosfm/io/bag_container.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/euroc_writer.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/ros_messages.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

bool IsIdentity(const Rigid3d& transform) {
  return transform.rotation.angularDistance(Eigen::Quaterniond::Identity()) < 1e-12 &&
         transform.translation.norm() < 1e-12;
}

std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? separator : "") + parts[i];
  return out;
}

// The message types viosfm reads, by what they hold.
enum class Kind { kImage, kCompressedImage, kImu, kPoseStamped, kTransformStamped, kString };

const RosMessageType& TypeOf(BagFormat format, Kind kind) {
  const bool ros1 = format == BagFormat::kRos1;
  switch (kind) {
    case Kind::kImage: return ros1 ? kRosImageType : kRos2ImageType;
    case Kind::kCompressedImage: return ros1 ? kRosCompressedImageType : kRos2CompressedImageType;
    case Kind::kImu: return ros1 ? kRosImuType : kRos2ImuType;
    case Kind::kPoseStamped: return ros1 ? kRosPoseStampedType : kRos2PoseStampedType;
    case Kind::kTransformStamped:
      return ros1 ? kRosTransformStampedType : kRos2TransformStampedType;
    case Kind::kString: return ros1 ? kRosStringType : kRos2StringType;
  }
  return kRosStringType;
}

// The kind of a connection's type, if viosfm reads it. ROS 2 types are
// compared in their current form ("sensor_msgs/msg/Image").
std::optional<Kind> KindOf(BagFormat format, const std::string& type) {
  const std::string name = format == BagFormat::kRos2 ? NormalizeRos2TypeName(type) : type;
  for (const Kind kind : {Kind::kImage, Kind::kCompressedImage, Kind::kImu, Kind::kPoseStamped,
                          Kind::kTransformStamped, Kind::kString}) {
    if (name == TypeOf(format, kind).name) return kind;
  }
  return std::nullopt;
}

// The connections of each topic.
using TopicMap = std::map<std::string, std::vector<const BagConnection*>>;

TopicMap GroupByTopic(const BagReader& reader) {
  TopicMap topics;
  for (const BagConnection& connection : reader.connections()) {
    topics[connection.topic].push_back(&connection);
  }
  return topics;
}

// The serialization a connection must have for viosfm to decode it.
bool DecodableSerialization(const BagReader& reader, const BagConnection& connection) {
  return reader.format() == BagFormat::kRos1 || connection.serialization == "cdr";
}

// Picks a topic: the requested one (which must exist and have an accepted
// type), else the only topic of an accepted type, else `preferred` among
// several. Returns "" when the bag has none and `required` is false.
std::string ChooseTopic(const BagReader& reader, const TopicMap& topics,
                        const std::string& requested, const std::vector<Kind>& kinds,
                        const std::string& preferred, const std::string& what,
                        const std::string& flag, bool required) {
  const std::string p = reader.path().string();
  std::vector<std::string> type_names;
  for (const Kind kind : kinds) type_names.push_back(TypeOf(reader.format(), kind).name);
  const std::string type_list = Join(type_names, " or ");
  const auto accepted = [&](const BagConnection& connection) {
    const std::optional<Kind> kind = KindOf(reader.format(), connection.type);
    return kind && std::find(kinds.begin(), kinds.end(), *kind) != kinds.end();
  };
  if (!requested.empty()) {
    const auto it = topics.find(requested);
    if (it == topics.end()) {
      throw InputError(p, 0,
                       "no topic '" + requested + "' (" + flag + "); the bag has:\n" +
                           DescribeBagTopics(reader));
    }
    for (const BagConnection* connection : it->second) {
      if (!accepted(*connection)) {
        throw InputError(p, 0,
                         "topic '" + requested + "' (" + flag + ") has type " + connection->type +
                             ", expected " + type_list);
      }
      if (!DecodableSerialization(reader, *connection)) {
        throw InputError(p, 0,
                         "topic '" + requested + "' (" + flag + ") is serialized as '" +
                             connection->serialization +
                             "': viosfm reads ROS 2 messages in CDR (rmw_fastrtps_cpp, "
                             "rmw_cyclonedds_cpp)");
      }
    }
    return requested;
  }
  std::vector<std::string> candidates;
  for (const auto& [topic, connections] : topics) {
    if (accepted(*connections.front()) && DecodableSerialization(reader, *connections.front())) {
      candidates.push_back(topic);
    }
  }
  if (candidates.size() == 1) return candidates.front();
  if (candidates.empty()) {
    if (!required) return "";
    throw InputError(
        p, 0,
        "no " + what + " topic (" + type_list + "); the bag has:\n" + DescribeBagTopics(reader));
  }
  if (std::find(candidates.begin(), candidates.end(), preferred) != candidates.end()) {
    VIOSFM_LOG(INFO) << p << ": " << candidates.size() << " " << what << " topics, reading "
                     << preferred << " (EuRoC's name; choose another with " << flag << ")";
    return preferred;
  }
  throw InputError(p, 0,
                   std::to_string(candidates.size()) + " " + what + " topics (" +
                       Join(candidates, ", ") + "): choose one with " + flag);
}

// ROS 1 only: a connection's MD5 sum says which definition of the type it has.
void CheckMd5(const BagReader& reader, const TopicMap& topics, const std::string& topic) {
  if (topic.empty() || reader.format() != BagFormat::kRos1) return;
  for (const BagConnection* connection : topics.at(topic)) {
    const std::optional<Kind> kind = KindOf(reader.format(), connection->type);
    VIOSFM_CHECK(kind.has_value()) << connection->type;
    const RosMessageType& known = TypeOf(reader.format(), *kind);
    if (connection->md5sum != "*" && connection->md5sum != known.md5sum) {
      throw InputError(reader.path().string(), 0,
                       "topic '" + topic + "': " + connection->type + " with MD5 sum " +
                           connection->md5sum + ", expected " + known.md5sum +
                           " (a different definition of the message)");
    }
  }
}

// The message decoders of a bag's serialization.
struct Decoders {
  RosImage (*image)(std::span<const uint8_t>, const std::string&);
  RosCompressedImage (*compressed_image)(std::span<const uint8_t>, const std::string&);
  RosImu (*imu)(std::span<const uint8_t>, const std::string&);
  RosPoseStamped (*pose_stamped)(std::span<const uint8_t>, const std::string&);
  RosTransformStamped (*transform_stamped)(std::span<const uint8_t>, const std::string&);
  std::string (*string)(std::span<const uint8_t>, const std::string&);
};

Decoders DecodersOf(BagFormat format) {
  if (format == BagFormat::kRos1) {
    return {DeserializeRosImage,       DeserializeRosCompressedImage,  DeserializeRosImu,
            DeserializeRosPoseStamped, DeserializeRosTransformStamped, DeserializeRosString};
  }
  return {DeserializeCdrImage,       DeserializeCdrCompressedImage,  DeserializeCdrImu,
          DeserializeCdrPoseStamped, DeserializeCdrTransformStamped, DeserializeCdrString};
}

// Converts a sensor_msgs/Image to grey; InputError for encodings viosfm
// does not read or sizes that do not add up.
GreyImage ImageToGrey(const RosImage& image, const std::string& where) {
  const std::string encoding = ToLower(image.encoding);
  int channels = 0;
  int conversion = -1;
  if (encoding == "mono8" || encoding == "8uc1") {
    channels = 1;
  } else if (encoding == "bgr8" || encoding == "8uc3") {
    channels = 3;
    conversion = cv::COLOR_BGR2GRAY;
  } else if (encoding == "rgb8") {
    channels = 3;
    conversion = cv::COLOR_RGB2GRAY;
  } else if (encoding == "bgra8" || encoding == "8uc4") {
    channels = 4;
    conversion = cv::COLOR_BGRA2GRAY;
  } else if (encoding == "rgba8") {
    channels = 4;
    conversion = cv::COLOR_RGBA2GRAY;
  } else {
    throw InputError(where + ": sensor_msgs/Image encoding '" + image.encoding +
                     "' is not supported (expected mono8, bgr8, rgb8, bgra8 or rgba8)");
  }
  if (image.width == 0 || image.height == 0 || image.width > 100000 || image.height > 100000) {
    throw InputError(where + ": sensor_msgs/Image of " + std::to_string(image.width) + "x" +
                     std::to_string(image.height) + " pixels");
  }
  const uint64_t row_bytes = uint64_t{image.width} * channels;
  if (image.step < row_bytes) {
    throw InputError(where + ": sensor_msgs/Image step " + std::to_string(image.step) +
                     " is shorter than a row of " + std::to_string(image.width) + " " + encoding +
                     " pixels (" + std::to_string(row_bytes) + " bytes)");
  }
  if (image.data.size() != uint64_t{image.step} * image.height) {
    throw InputError(where + ": sensor_msgs/Image data has " + std::to_string(image.data.size()) +
                     " bytes, expected step x height = " + std::to_string(image.step) + " x " +
                     std::to_string(image.height));
  }
  const int width = static_cast<int>(image.width);
  const int height = static_cast<int>(image.height);
  const cv::Mat source(height, width, CV_8UC(channels), const_cast<uint8_t*>(image.data.data()),
                       image.step);
  cv::Mat grey;
  if (conversion < 0) {
    grey = source;
  } else {
    cv::cvtColor(source, grey, conversion);
  }
  GreyImage out(width, height);
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = grey.ptr<uint8_t>(y);
    std::copy(row, row + width, out.pixels.begin() + static_cast<size_t>(y) * width);
  }
  return out;
}

GreyImage CompressedImageToGrey(const RosCompressedImage& image, const std::string& where) {
  const std::string format = ToLower(image.format);
  if (format.find("compresseddepth") != std::string::npos) {
    throw InputError(where + ": sensor_msgs/CompressedImage format '" + image.format +
                     "' is a depth image, not a camera image");
  }
  cv::Mat grey;
  try {
    const cv::Mat bytes(1, static_cast<int>(image.data.size()), CV_8UC1,
                        const_cast<uint8_t*>(image.data.data()));
    grey = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    throw InputError(where + ": sensor_msgs/CompressedImage (format '" + image.format +
                     "') cannot be decoded: " + e.what());
  }
  if (grey.empty() || grey.type() != CV_8UC1) {
    throw InputError(where + ": sensor_msgs/CompressedImage (format '" + image.format + "', " +
                     std::to_string(image.data.size()) +
                     " bytes) cannot be decoded (expected JPEG or PNG data)");
  }
  GreyImage out(grey.cols, grey.rows);
  for (int y = 0; y < grey.rows; ++y) {
    const uint8_t* row = grey.ptr<uint8_t>(y);
    std::copy(row, row + grey.cols, out.pixels.begin() + static_cast<size_t>(y) * grey.cols);
  }
  return out;
}

// ".jpg" or ".png" when `data` is a JPEG or PNG file (by its first bytes),
// else "".
std::string FileExtensionOf(const std::vector<uint8_t>& data) {
  static constexpr uint8_t kJpeg[] = {0xff, 0xd8, 0xff};
  static constexpr uint8_t kPng[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (data.size() >= sizeof(kJpeg) && std::equal(kJpeg, kJpeg + sizeof(kJpeg), data.begin())) {
    return ".jpg";
  }
  if (data.size() >= sizeof(kPng) && std::equal(kPng, kPng + sizeof(kPng), data.begin())) {
    return ".png";
  }
  return "";
}

struct Located {
  timestamp_ns_t stamp_ns = 0;
  std::string location;
};

// Sorts by stamp; equal stamps are an error naming both messages.
template <typename T>
void SortByStamp(std::vector<std::pair<Located, T>>* items, const std::string& bag,
                 const std::string& topic) {
  std::stable_sort(items->begin(), items->end(), [](const auto& a, const auto& b) {
    return a.first.stamp_ns < b.first.stamp_ns;
  });
  for (size_t i = 1; i < items->size(); ++i) {
    if ((*items)[i].first.stamp_ns == (*items)[i - 1].first.stamp_ns) {
      throw InputError(bag, 0,
                       "topic '" + topic + "': two messages with the stamp " +
                           std::to_string((*items)[i].first.stamp_ns) + " ns (" +
                           (*items)[i - 1].first.location + " and " + (*items)[i].first.location +
                           ")");
    }
  }
}

}  // namespace

std::string RosbagDatasetOptions::Validate() const {
  if (extract_folder.empty()) return "extract_folder must be given (where the images are written)";
  if (!imu_yaml.empty() && camera_yaml.empty()) {
    return "imu_yaml needs camera_yaml (the camera calibration) too";
  }
  if (rig && !camera_yaml.empty()) return "give either rig or camera_yaml, not both";
  if (rig) {
    if (const std::string problem = rig->Validate(); !problem.empty()) return "rig: " + problem;
  }
  return "";
}

std::string RosbagWriteOptions::Validate() const {
  const auto valid_topic = [](const std::string& topic) {
    if (topic.empty()) return false;
    return std::all_of(topic.begin(), topic.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/' || c == '~';
    });
  };
  if (!valid_topic(image_topic)) return "image_topic '" + image_topic + "' is not a ROS topic name";
  if (!valid_topic(imu_topic)) return "imu_topic '" + imu_topic + "' is not a ROS topic name";
  if (!valid_topic(groundtruth_topic)) {
    return "groundtruth_topic '" + groundtruth_topic + "' is not a ROS topic name";
  }
  if (image_topic == imu_topic || image_topic == groundtruth_topic ||
      imu_topic == groundtruth_topic) {
    return "the image, IMU and ground-truth topics must differ";
  }
  if (writer.chunk_threshold_bytes == 0) return "writer.chunk_threshold_bytes must be positive";
  return "";
}

std::string DescribeBagTopics(const BagReader& reader) {
  std::ostringstream out;
  const TopicMap topics = GroupByTopic(reader);
  if (topics.empty()) return "  (no topics)";
  bool first = true;
  for (const auto& [topic, connections] : topics) {
    uint64_t count = 0;
    for (const BagConnection* connection : connections) count += connection->num_messages;
    const BagConnection& connection = *connections.front();
    out << (first ? "" : "\n") << "  " << topic << " (" << connection.type << ", "
        << (DecodableSerialization(reader, connection)
                ? ""
                : "serialized as '" + connection.serialization + "', ")
        << count << (count == 1 ? " message)" : " messages)");
    first = false;
  }
  return out.str();
}

namespace {

// Reads a bag into a Sequence in named steps: the topics chosen, the
// messages taken (images written into the extract folder as they come), the
// sequence built, its calibration found, then checked.
class RosbagDatasetReader {
 public:
  RosbagDatasetReader(const fs::path& bag, const RosbagDatasetOptions& options)
      : bag_(bag),
        options_(options),
        bag_reader_(OpenBag(bag)),
        reader_(*bag_reader_),
        format_(reader_.format()),
        decode_(DecodersOf(format_)),
        p_(bag.string()),
        topics_(GroupByTopic(reader_)),
        mav0_(options.extract_folder / "mav0"),
        image_folder_(mav0_ / "cam0" / "data") {}

  Sequence Read() {
    ChooseTopics();
    CreateImageFolder();
    TakeMessages();
    BuildSequence();
    FindCalibration();
    ApplyCalibration();
    CheckSequence();
    // The extract folder is a EuRoC folder of what was read.
    WriteEurocDataset(options_.extract_folder, sequence_);
    VIOSFM_LOG(INFO) << "bag " << p_ << ": " << sequence_.images.size() << " images on "
                     << image_topic_ << ", " << sequence_.imu.size() << " IMU samples"
                     << LogDetails() << " (" << sequence_.rig.camera.ModelName() << " "
                     << image_width_ << "x" << image_height_ << ")"
                     << (imu_topic_.empty() ? "" : " on " + imu_topic_) << ", "
                     << sequence_.ground_truth.size() << " ground-truth poses; calibration from "
                     << calibration_source_ << "; images in " << image_folder_.string();
    return std::move(sequence_);
  }

 private:
  // The image, IMU and ground-truth topics (each checked against its
  // message definition), and whether the bag's own calibration is read.
  void ChooseTopics() {
    image_topic_ =
        ChooseTopic(reader_, topics_, options_.image_topic, {Kind::kImage, Kind::kCompressedImage},
                    kEurocImageTopic, "image", "--image-topic", /*required=*/true);
    imu_topic_ = ChooseTopic(reader_, topics_, options_.imu_topic, {Kind::kImu}, kEurocImuTopic,
                             "IMU", "--imu-topic", options_.require_imu);
    groundtruth_topic_ = options_.groundtruth_topic;
    if (groundtruth_topic_.empty() && topics_.count(kGroundTruthTopic) > 0) {
      groundtruth_topic_ = kGroundTruthTopic;
    }
    if (!groundtruth_topic_.empty()) {
      ChooseTopic(reader_, topics_, groundtruth_topic_,
                  {Kind::kPoseStamped, Kind::kTransformStamped}, "", "ground-truth",
                  "--groundtruth-topic", true);
    }
    for (const std::string& topic : {image_topic_, imu_topic_, groundtruth_topic_}) {
      CheckMd5(reader_, topics_, topic);
    }
    if (imu_topic_.empty()) {
      VIOSFM_LOG(WARNING) << p_ << ": no sensor_msgs/Imu topic: a sequence without IMU";
    }
    read_embedded_ =
        !options_.rig && options_.camera_yaml.empty() && HasStringTopic(kCameraCalibrationTopic);
  }

  // Whether `topic` is a decodable std_msgs/String topic of the bag.
  bool HasStringTopic(const char* topic) const {
    const auto it = topics_.find(topic);
    return it != topics_.end() &&
           KindOf(format_, it->second.front()->type) == std::optional<Kind>(Kind::kString) &&
           DecodableSerialization(reader_, *it->second.front());
  }

  void CreateImageFolder() const {
    std::error_code error;
    fs::create_directories(image_folder_, error);
    if (error) {
      throw InputError(image_folder_.string(), 0, "cannot create the folder: " + error.message());
    }
  }

  bool Wanted(const BagConnection& connection) const {
    return connection.topic == image_topic_ || connection.topic == imu_topic_ ||
           connection.topic == groundtruth_topic_ ||
           (read_embedded_ && (connection.topic == kCameraCalibrationTopic ||
                               connection.topic == kImuCalibrationTopic));
  }

  void TakeMessages() {
    reader_.ReadMessages([this](const BagConnection& connection) { return Wanted(connection); },
                         [this](const BagMessage& message) { TakeMessage(message); });
    if (images_.empty()) {
      throw InputError(p_, 0, "topic '" + image_topic_ + "' has no messages");
    }
    if (num_unstamped_ > 0) {
      VIOSFM_LOG(WARNING) << p_ << ": " << num_unstamped_
                          << " messages without a header stamp were stamped with their record "
                             "time";
    }
  }

  void TakeMessage(const BagMessage& message) {
    const std::string& topic = message.connection->topic;
    const std::string where = p_ + ": " + message.location + " (" + topic + ")";
    if (topic == image_topic_) {
      TakeImage(message, where);
    } else if (topic == imu_topic_) {
      TakeImu(message, where);
    } else if (topic == groundtruth_topic_) {
      TakeGroundTruth(message, where);
    } else if (topic == kCameraCalibrationTopic) {
      camera_yaml_text_ = decode_.string(message.data, where);
    } else if (topic == kImuCalibrationTopic) {
      imu_yaml_text_ = decode_.string(message.data, where);
    }
  }

  // A message without a header stamp is stamped with its record time.
  timestamp_ns_t StampOf(const RosHeader& header, const BagMessage& message) {
    if (header.stamp_ns != 0) return header.stamp_ns;
    ++num_unstamped_;
    return message.time_ns;
  }

  void TakeImage(const BagMessage& message, const std::string& where) {
    GreyImage grey;
    timestamp_ns_t stamp = 0;
    std::string file_extension;  // of a CompressedImage kept as its file
    std::vector<uint8_t> file_bytes;
    if (KindOf(format_, message.connection->type) == std::optional<Kind>(Kind::kImage)) {
      const RosImage image = decode_.image(message.data, where);
      stamp = StampOf(image.header, message);
      grey = ImageToGrey(image, where);
    } else {
      RosCompressedImage image = decode_.compressed_image(message.data, where);
      stamp = StampOf(image.header, message);
      grey = CompressedImageToGrey(image, where);
      file_extension = FileExtensionOf(image.data);
      if (!file_extension.empty()) file_bytes = std::move(image.data);
    }
    CheckImage(grey, stamp, message.location, where);
    // A JPEG or PNG file is kept as it is (its name then is the one a
    // EuRoC folder of JPEG images has); anything else is written as PNG.
    const fs::path path = image_folder_ / (std::to_string(stamp) +
                                           (file_extension.empty() ? ".png" : file_extension));
    if (file_extension.empty()) {
      WriteGreyPng(path, grey);
    } else {
      WriteFileAtomically(
          path,
          [&](std::ostream& out) {
            out.write(reinterpret_cast<const char*>(file_bytes.data()),
                      static_cast<std::streamsize>(file_bytes.size()));
          },
          /*binary=*/true);
    }
    images_.push_back({{stamp, message.location}, path});
  }

  // Every image of the first one's size, each stamp once.
  void CheckImage(const GreyImage& grey, timestamp_ns_t stamp, const std::string& location,
                  const std::string& where) {
    if (first_image_location_.empty()) {
      image_width_ = grey.width;
      image_height_ = grey.height;
      first_image_location_ = location;
    } else if (grey.width != image_width_ || grey.height != image_height_) {
      throw InputError(where + ": image of " + std::to_string(grey.width) + "x" +
                       std::to_string(grey.height) + " pixels, the first one (" +
                       first_image_location_ + ") has " + std::to_string(image_width_) + "x" +
                       std::to_string(image_height_));
    }
    if (!image_stamps_.insert(stamp).second) {
      throw InputError(where + ": a second image with the stamp " + std::to_string(stamp) + " ns");
    }
  }

  void TakeImu(const BagMessage& message, const std::string& where) {
    const RosImu message_imu = decode_.imu(message.data, where);
    ImuSample sample;
    sample.timestamp_ns = StampOf(message_imu.header, message);
    sample.gyro = message_imu.angular_velocity;
    sample.accel = message_imu.linear_acceleration;
    if (!sample.gyro.allFinite() || !sample.accel.allFinite()) {
      throw InputError(where +
                       ": sensor_msgs/Imu with a non-finite angular velocity or "
                       "linear acceleration");
    }
    imu_.push_back({{sample.timestamp_ns, message.location}, sample});
  }

  void TakeGroundTruth(const BagMessage& message, const std::string& where) {
    RosHeader header;
    Rigid3d world_from_body;
    if (KindOf(format_, message.connection->type) == std::optional<Kind>(Kind::kPoseStamped)) {
      const RosPoseStamped pose = decode_.pose_stamped(message.data, where);
      header = pose.header;
      world_from_body = pose.pose;
    } else {
      const RosTransformStamped transform = decode_.transform_stamped(message.data, where);
      header = transform.header;
      world_from_body = transform.transform;
    }
    const double norm = world_from_body.rotation.norm();
    if (!(std::abs(norm - 1.0) <= 1e-3) || !world_from_body.translation.allFinite()) {
      throw InputError(where + ": ground-truth pose with a quaternion of norm " +
                       std::to_string(norm) + " (expected 1) or a non-finite position");
    }
    // As the trajectory readers do: a quaternion already of unit norm
    // (to rounding) is kept as it is, so a pose survives a bag exactly.
    if (std::abs(world_from_body.rotation.squaredNorm() - 1.0) > 2e-15) {
      world_from_body.rotation.normalize();
    }
    ground_truth_.push_back({{StampOf(header, message), message.location}, world_from_body});
  }

  void BuildSequence() {
    SortByStamp(&images_, p_, image_topic_);
    SortByStamp(&imu_, p_, imu_topic_);
    SortByStamp(&ground_truth_, p_, groundtruth_topic_);
    sequence_.root = bag_;
    for (const auto& [located, path] : images_) {
      sequence_.images.push_back({located.stamp_ns, path});
    }
    for (const auto& [located, sample] : imu_) sequence_.imu.push_back(sample);
  }

  // The camera and IMU sensor.yaml files (the IMU's may be empty).
  void ReadYamlPair(const fs::path& camera_yaml, const fs::path& imu_yaml) {
    const EurocCameraCalibration camera = ReadEurocCameraYaml(camera_yaml);
    sequence_.rig.camera = camera.camera;
    sequence_.rig.body_from_cam = camera.body_from_cam;
    sequence_.rig.camera_rate_hz = camera.rate_hz;
    if (!imu_yaml.empty()) {
      const EurocImuCalibration imu_calibration = ReadEurocImuYaml(imu_yaml);
      sequence_.rig.imu_noise = imu_calibration.noise;
      body_from_imu_ = imu_calibration.body_from_imu;
      has_imu_calibration_ = true;
    }
  }

  // The calibration: given in code, as sensor.yaml files, in the bag, or in
  // the EuRoC folder beside it, in that order.
  void FindCalibration() {
    const fs::path beside = bag_.parent_path() / "mav0";
    if (options_.rig) {
      sequence_.rig = *options_.rig;
      has_imu_calibration_ = true;
      calibration_source_ = "the calibration given in code";
    } else if (!options_.camera_yaml.empty()) {
      ReadYamlPair(options_.camera_yaml, options_.imu_yaml);
      calibration_source_ = options_.camera_yaml.string() +
                            (options_.imu_yaml.empty() ? "" : " and " + options_.imu_yaml.string());
    } else if (!camera_yaml_text_.empty()) {
      ReadEmbeddedCalibration();
    } else if (fs::is_regular_file(beside / "cam0" / "sensor.yaml")) {
      const fs::path imu_yaml = beside / "imu0" / "sensor.yaml";
      ReadYamlPair(beside / "cam0" / "sensor.yaml",
                   fs::is_regular_file(imu_yaml) ? imu_yaml : fs::path());
      calibration_source_ = "the EuRoC folder beside the bag (" + beside.string() + ")";
    } else {
      throw InputError(p_, 0,
                       "no camera calibration: give the EuRoC/Kalibr sensor.yaml files "
                       "(--camera-yaml cam0/sensor.yaml --imu-yaml imu0/sensor.yaml), or put the "
                       "EuRoC folder's mav0/ beside the bag (" +
                           beside.string() + ")");
    }
  }

  // The bag's calibration topics, written as the extract folder's sensor.yaml files.
  void ReadEmbeddedCalibration() {
    const fs::path camera_yaml = mav0_ / "cam0" / "sensor.yaml";
    const fs::path imu_yaml = mav0_ / "imu0" / "sensor.yaml";
    WriteFileAtomically(camera_yaml, [&](std::ostream& out) { out << camera_yaml_text_; });
    if (!imu_yaml_text_.empty()) {
      fs::create_directories(imu_yaml.parent_path());
      WriteFileAtomically(imu_yaml, [&](std::ostream& out) { out << imu_yaml_text_; });
    }
    ReadYamlPair(camera_yaml, imu_yaml_text_.empty() ? fs::path() : imu_yaml);
    calibration_source_ =
        std::string("the bag's ") + kCameraCalibrationTopic +
        (imu_yaml_text_.empty() ? "" : std::string(" and ") + kImuCalibrationTopic);
  }

  // The IMU's rate without its calibration, the rig in the IMU's frame, the
  // ground truth, and the camera's rate.
  void ApplyCalibration() {
    if (sequence_.has_imu() && !has_imu_calibration_) TakeImuRateFromTheStamps();
    if (!IsIdentity(body_from_imu_)) {
      VIOSFM_LOG(WARNING) << p_ << ": the IMU calibration's T_BS is not the identity; camera "
                          << "extrinsics and ground-truth poses are re-expressed in the IMU "
                             "frame";
      sequence_.rig.body_from_cam = body_from_imu_.Inverse() * sequence_.rig.body_from_cam;
    }
    for (const auto& [located, world_from_body] : ground_truth_) {
      GroundTruthState state;
      state.timestamp_ns = located.stamp_ns;
      // (Composed only when needed: composing normalises the quaternion.)
      state.world_from_body =
          IsIdentity(body_from_imu_) ? world_from_body : world_from_body * body_from_imu_;
      sequence_.ground_truth.push_back(state);
    }
    if (!(sequence_.rig.camera_rate_hz > 0)) {
      sequence_.rig.camera_rate_hz = EstimateFrameRateHz(sequence_.images);
    }
  }

  // The noise densities keep their defaults; the rate is the IMU's median.
  void TakeImuRateFromTheStamps() {
    std::vector<timestamp_ns_t> intervals;
    for (size_t i = 1; i < sequence_.imu.size(); ++i) {
      intervals.push_back(sequence_.imu[i].timestamp_ns - sequence_.imu[i - 1].timestamp_ns);
    }
    if (!intervals.empty()) {
      std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2,
                       intervals.end());
      sequence_.rig.imu_noise.rate_hz = 1e9 / static_cast<double>(intervals[intervals.size() / 2]);
    }
    VIOSFM_LOG(WARNING) << p_ << ": no IMU calibration (imu0/sensor.yaml): the IMU noise "
                        << "densities keep their defaults (EuRoC's ADIS16448), rate "
                        << sequence_.rig.imu_noise.rate_hz << " Hz from the stamps";
  }

  // The images' size against the calibration's, the rig, the IMU's coverage.
  void CheckSequence() const {
    const Camera& camera = sequence_.rig.camera;
    if (static_cast<int64_t>(camera.width) != image_width_ ||
        static_cast<int64_t>(camera.height) != image_height_) {
      throw InputError(p_, 0,
                       "the images on '" + image_topic_ + "' have " + std::to_string(image_width_) +
                           "x" + std::to_string(image_height_) + " pixels, the calibration (" +
                           calibration_source_ + ") states " + std::to_string(camera.width) + "x" +
                           std::to_string(camera.height));
    }
    if (const std::string problem = sequence_.rig.Validate(); !problem.empty()) {
      throw InputError(p_, 0, "calibration (" + calibration_source_ + "): " + problem);
    }
    if (sequence_.has_imu()) {
      const ImuCoverage coverage = CheckImuCoverage(sequence_);
      if (!coverage.overlaps) {
        throw InputError(
            p_, 0, "topic '" + imu_topic_ + "': no IMU sample over the images: " + coverage.spans);
      }
      if (!coverage.complete) {
        VIOSFM_LOG(WARNING) << p_ << ": the IMU does not cover the whole image time span: "
                            << coverage.spans;
      }
    }
  }

  const fs::path& bag_;
  const RosbagDatasetOptions& options_;
  const std::unique_ptr<BagReader> bag_reader_;
  BagReader& reader_;
  const BagFormat format_;
  const Decoders decode_;
  const std::string p_;
  const TopicMap topics_;
  const fs::path mav0_;
  const fs::path image_folder_;

  std::string image_topic_, imu_topic_, groundtruth_topic_;
  bool read_embedded_ = false;

  std::vector<std::pair<Located, fs::path>> images_;
  std::vector<std::pair<Located, ImuSample>> imu_;
  std::vector<std::pair<Located, Rigid3d>> ground_truth_;
  std::set<timestamp_ns_t> image_stamps_;
  std::string camera_yaml_text_, imu_yaml_text_;
  int image_width_ = 0, image_height_ = 0;
  std::string first_image_location_;
  size_t num_unstamped_ = 0;

  Sequence sequence_;
  std::string calibration_source_;
  Rigid3d body_from_imu_;
  bool has_imu_calibration_ = false;
};

}  // namespace

Sequence ReadRosbagDataset(const fs::path& bag, const RosbagDatasetOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw InputError("bag read options: " + problem);
  }
  return RosbagDatasetReader(bag, options).Read();
}

namespace {

// Writes a Sequence into a bag in named steps: the stamps checked against
// the bag's time type, the topics added, the calibration embedded, then the
// images, IMU samples and ground-truth poses merged by stamp.
class RosbagDatasetWriter {
 public:
  RosbagDatasetWriter(const Sequence& sequence, const fs::path& bag,
                      const RosbagWriteOptions& options)
      : sequence_(sequence),
        bag_(bag),
        options_(options),
        bag_writer_(CreateBagWriter(bag, options.writer)),
        writer_(*bag_writer_),
        ros1_(writer_.format() == BagFormat::kRos1) {}

  void Write() {
    CheckStamps();
    AddTopics();
    if (options_.embed_calibration) EmbedCalibration();
    WriteMessages();
    writer_.Close();
    VIOSFM_LOG(INFO) << "bag " << bag_.string() << ": wrote " << sequence_.images.size()
                     << " images on " << options_.image_topic << ", " << sequence_.imu.size()
                     << " IMU samples on " << options_.imu_topic << ", "
                     << sequence_.ground_truth.size() << " ground-truth poses";
  }

 private:
  // ROS time is uint32 seconds, ROS 2's builtin_interfaces/Time int32 seconds.
  void CheckStamps() const {
    const timestamp_ns_t max_stamp =
        (ros1_ ? timestamp_ns_t{0xffffffff} : timestamp_ns_t{0x7fffffff}) * 1'000'000'000 +
        999'999'999;
    const auto check_stamp = [&](timestamp_ns_t stamp, const char* what) {
      if (stamp < 0 || stamp > max_stamp) {
        throw InputError(bag_.string(), 0,
                         std::string(what) + " stamp " + std::to_string(stamp) + " ns is outside " +
                             (ros1_ ? "ROS time (0 to 2^32 s)" : "ROS 2 time (0 to 2^31 s)"));
      }
    };
    for (const SequenceImage& image : sequence_.images) check_stamp(image.timestamp_ns, "image");
    for (const ImuSample& sample : sequence_.imu) check_stamp(sample.timestamp_ns, "IMU");
    for (const GroundTruthState& state : sequence_.ground_truth) {
      check_stamp(state.timestamp_ns, "ground-truth");
    }
  }

  void AddTopics() {
    image_connection_ = writer_.AddTopic(
        options_.image_topic,
        options_.compressed_images ? BagMessageKind::kCompressedImage : BagMessageKind::kImage);
    if (sequence_.has_imu()) {
      imu_connection_ = writer_.AddTopic(options_.imu_topic, BagMessageKind::kImu);
    }
    if (sequence_.has_ground_truth()) {
      groundtruth_connection_ =
          writer_.AddTopic(options_.groundtruth_topic, BagMessageKind::kPoseStamped);
    }
  }

  // The sensor.yaml texts on their topics, stamped with the first message's stamp.
  void EmbedCalibration() {
    const auto serialize_string = ros1_ ? SerializeRosString : SerializeCdrString;
    timestamp_ns_t first = sequence_.images.front().timestamp_ns;
    if (sequence_.has_imu()) first = std::min(first, sequence_.imu.front().timestamp_ns);
    if (sequence_.has_ground_truth()) {
      first = std::min(first, sequence_.ground_truth.front().timestamp_ns);
    }
    const SensorRig& rig = sequence_.rig;
    const uint32_t camera = writer_.AddTopic(kCameraCalibrationTopic, BagMessageKind::kString);
    writer_.Write(camera, first,
                  serialize_string(!options_.camera_yaml_text.empty()
                                       ? options_.camera_yaml_text
                                       : EurocCameraYamlText(rig.camera, rig.body_from_cam,
                                                             rig.camera_rate_hz)));
    if (sequence_.has_imu()) {
      const uint32_t imu = writer_.AddTopic(kImuCalibrationTopic, BagMessageKind::kString);
      writer_.Write(
          imu, first,
          serialize_string(!options_.imu_yaml_text.empty() ? options_.imu_yaml_text
                                                           : EurocImuYamlText(rig.imu_noise)));
    }
  }

  // Merges the three streams by stamp (images first on ties, then IMU).
  void WriteMessages() {
    size_t i_image = 0, i_imu = 0, i_gt = 0;
    constexpr timestamp_ns_t kEnd = std::numeric_limits<timestamp_ns_t>::max();
    const auto& images = sequence_.images;
    const auto& imu = sequence_.imu;
    const auto& ground_truth = sequence_.ground_truth;
    while (i_image < images.size() || i_imu < imu.size() || i_gt < ground_truth.size()) {
      const timestamp_ns_t t_image = i_image < images.size() ? images[i_image].timestamp_ns : kEnd;
      const timestamp_ns_t t_imu = i_imu < imu.size() ? imu[i_imu].timestamp_ns : kEnd;
      const timestamp_ns_t t_gt =
          i_gt < ground_truth.size() ? ground_truth[i_gt].timestamp_ns : kEnd;
      if (t_image <= t_imu && t_image <= t_gt) {
        WriteImage(i_image++);
      } else if (t_imu <= t_gt) {
        WriteImu(i_imu++);
      } else {
        WriteGroundTruth(i_gt++);
      }
    }
  }

  void WriteImage(size_t index) {
    const SequenceImage& image = sequence_.images[index];
    const RosHeader header{static_cast<uint32_t>(index), image.timestamp_ns, "cam0"};
    std::vector<uint8_t> bytes;
    if (options_.compressed_images) {
      RosCompressedImage message;
      message.header = header;
      const std::string extension = ToLower(image.path.extension().string());
      if (extension == ".png") {
        message.format = "png";
      } else if (extension == ".jpg" || extension == ".jpeg") {
        message.format = "jpeg";
      } else {
        throw InputError(image.path.string(), 0,
                         "expected a .png or .jpg image to store as sensor_msgs/CompressedImage");
      }
      const std::string file = ReadTextFile(image.path);
      message.data.assign(file.begin(), file.end());
      bytes = ros1_ ? SerializeRosCompressedImage(message) : SerializeCdrCompressedImage(message);
    } else {
      const GreyImage grey = ReadGreyImage(image.path);
      RosImage message;
      message.header = header;
      message.height = static_cast<uint32_t>(grey.height);
      message.width = static_cast<uint32_t>(grey.width);
      message.encoding = "mono8";
      message.step = static_cast<uint32_t>(grey.width);
      message.data = grey.pixels;
      bytes = ros1_ ? SerializeRosImage(message) : SerializeCdrImage(message);
    }
    writer_.Write(image_connection_, image.timestamp_ns, bytes);
  }

  void WriteImu(size_t index) {
    const ImuSample& sample = sequence_.imu[index];
    RosImu message;
    message.header = {static_cast<uint32_t>(index), sample.timestamp_ns, "imu0"};
    message.angular_velocity = sample.gyro;
    message.linear_acceleration = sample.accel;
    // ROS: orientation_covariance[0] = -1 says "no orientation estimate".
    message.orientation_covariance(0, 0) = -1.0;
    writer_.Write(imu_connection_, sample.timestamp_ns,
                  ros1_ ? SerializeRosImu(message) : SerializeCdrImu(message));
  }

  void WriteGroundTruth(size_t index) {
    const GroundTruthState& state = sequence_.ground_truth[index];
    RosPoseStamped message;
    message.header = {static_cast<uint32_t>(index), state.timestamp_ns, "world"};
    message.pose = state.world_from_body;
    writer_.Write(groundtruth_connection_, state.timestamp_ns,
                  ros1_ ? SerializeRosPoseStamped(message) : SerializeCdrPoseStamped(message));
  }

  const Sequence& sequence_;
  const fs::path& bag_;
  const RosbagWriteOptions& options_;
  const std::unique_ptr<BagWriter> bag_writer_;
  BagWriter& writer_;
  const bool ros1_;
  uint32_t image_connection_ = 0;
  uint32_t imu_connection_ = 0;
  uint32_t groundtruth_connection_ = 0;
};

}  // namespace

void WriteRosbagDataset(const Sequence& sequence, const fs::path& bag,
                        const RosbagWriteOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw InputError("bag write options: " + problem);
  }
  if (sequence.images.empty()) throw InputError(bag.string(), 0, "no images to write");
  RosbagDatasetWriter(sequence, bag, options).Write();
}

void UseEurocCalibrationTexts(const fs::path& folder, RosbagWriteOptions* options) {
  options->camera_yaml_text.clear();
  options->imu_yaml_text.clear();
  const fs::path mav0 = fs::is_directory(folder / "mav0") ? folder / "mav0" : folder;
  const fs::path camera = mav0 / "cam0" / "sensor.yaml";
  const fs::path imu = mav0 / "imu0" / "sensor.yaml";
  if (!fs::is_regular_file(camera)) return;
  if (fs::is_regular_file(imu)) {
    if (!IsIdentity(ReadEurocImuYaml(imu).body_from_imu)) return;
    options->imu_yaml_text = ReadTextFile(imu);
  }
  options->camera_yaml_text = ReadTextFile(camera);
}

}  // namespace viosfm

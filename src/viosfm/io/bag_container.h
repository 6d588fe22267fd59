// A recorded bag, whatever its container: a ROS 1 bag (rosbag.h) or a ROS 2
// bag (rosbag2.h: sqlite3 .db3 or MCAP .mcap files, alone or in a folder
// with metadata.yaml). rosbag_dataset.h reads a Sequence from any of them
// through this interface and writes one into any of them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "viosfm/io/ros_messages.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

// ROS 1 messages (ROS 1 serialization) or ROS 2 messages (CDR).
enum class BagFormat { kRos1, kRos2 };

// Whether `path` names a bag: a file ".bag" (ROS 1), ".db3" or ".mcap" (ROS
// 2; also ".db3.zstd", ".mcap.zstd": rosbag2's per-file compression), any
// case, or a folder holding metadata.yaml (a rosbag2 bag). The folder test
// looks at the file system; the extensions do not.
bool IsBagPath(const std::filesystem::path& path);

// Whether `path` is a bag by its extension alone (the file need not exist).
bool HasBagExtension(const std::filesystem::path& path);

// The files whose content makes up the bag at `path`: the file itself, or a
// rosbag2 folder's metadata.yaml and the storage files it lists (those that
// exist). Empty when `path` is not a bag.
std::vector<std::filesystem::path> BagFiles(const std::filesystem::path& path);

// One topic of a bag as one publisher recorded it (a ROS 1 connection, an
// MCAP channel, a rosbag2 topic); a topic may have several.
struct BagConnection {
  std::string topic;
  std::string type;           // as the bag names it: "sensor_msgs/Image", "sensor_msgs/msg/Image"
  std::string serialization;  // "ros1", or what a ROS 2 bag states ("cdr")
  std::string md5sum;         // ROS 1 only
  uint64_t num_messages = 0;
};

struct BagMessage {
  const BagConnection* connection = nullptr;
  timestamp_ns_t time_ns = 0;     // when it was recorded
  std::span<const uint8_t> data;  // the serialized message, valid during the callback
  // Where the message is, for error messages ("byte offset 5012",
  // "rec_0.db3, message 42").
  std::string location;
};

class BagReader {
 public:
  virtual ~BagReader() = default;
  virtual const std::filesystem::path& path() const = 0;
  virtual BagFormat format() const = 0;
  // "ROS 1 bag", "ROS 2 bag (sqlite3, 2 files, messages zstd-compressed)".
  virtual std::string Describe() const = 0;
  virtual const std::vector<BagConnection>& connections() const = 0;
  // Calls `visit` for every message whose connection `wanted` accepts, in
  // the order of the bag. Throws InputError on malformed data.
  virtual void ReadMessages(const std::function<bool(const BagConnection&)>& wanted,
                            const std::function<void(const BagMessage&)>& visit) = 0;
};

// Opens the bag at `path`, the container told by its content (a ROS 1 bag,
// an SQLite or MCAP file, a zstd-compressed one, a folder with
// metadata.yaml). Throws InputError naming the path when it is none of them
// or cannot be read.
std::unique_ptr<BagReader> OpenBag(const std::filesystem::path& path);

// The message kinds viosfm writes into bags.
enum class BagMessageKind { kImage, kCompressedImage, kImu, kPoseStamped, kString };

// The type of `kind` in `format` (kRosImageType, kRos2ImageType, ...).
const RosMessageType& BagMessageType(BagFormat format, BagMessageKind kind);

// Chunk compression of a written bag: ROS 1 none, bz2 or lz4; MCAP none,
// zstd or lz4; rosbag2 sqlite3 none or zstd (each message compressed).
enum class BagCompression { kDefault, kNone, kBz2, kLz4, kZstd };
// Parses "none", "bz2", "lz4", "zstd" (any case); InputError otherwise.
BagCompression ParseBagCompression(const std::string& name);
std::string BagCompressionName(BagCompression compression);

struct BagWriterOptions {
  // Default: ROS 1 none, MCAP zstd, sqlite3 none (rosbag2's defaults).
  BagCompression compression = BagCompression::kDefault;
  // A chunk is written when its uncompressed data exceeds this (ROS 1 and
  // MCAP). Default 768 KiB.
  size_t chunk_threshold_bytes = 768 * 1024;

  // Empty if valid for a bag at `path`; otherwise names the bad field.
  std::string Validate(const std::filesystem::path& path) const;
};

// Writes a bag atomically (a temporary file renamed by Close()).
class BagWriter {
 public:
  virtual ~BagWriter() = default;
  virtual BagFormat format() const = 0;
  // Returns the new topic's id.
  virtual uint32_t AddTopic(const std::string& topic, BagMessageKind kind) = 0;
  // `data` is serialized for format(); time_ns >= 0.
  virtual void Write(uint32_t topic_id, timestamp_ns_t time_ns, std::span<const uint8_t> data) = 0;
  virtual void Close() = 0;
};

// A writer for the container `path`'s extension names: ".bag" ROS 1,
// ".db3" rosbag2 sqlite3, ".mcap" MCAP (ROS 2 profile). InputError for any
// other extension or options the container does not take.
std::unique_ptr<BagWriter> CreateBagWriter(const std::filesystem::path& path,
                                           const BagWriterOptions& options = {});

}  // namespace viosfm

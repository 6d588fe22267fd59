#include "viosfm/io/bag_container.h"

#include <cstring>
#include <fstream>
#include <map>

#include "viosfm/io/mcap.h"
#include "viosfm/io/rosbag.h"
#include "viosfm/io/rosbag2.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// A ROS 1 bag (rosbag.h) seen as a BagReader: one BagConnection per ROS 1
// connection.
class Ros1BagReader : public BagReader {
 public:
  explicit Ros1BagReader(const fs::path& path) : reader_(path) {
    for (const RosbagConnection& connection : reader_.connections()) {
      index_[connection.id] = connections_.size();
      connections_.push_back(
          {connection.topic, connection.type, "ros1", connection.md5sum, connection.num_messages});
    }
  }

  const fs::path& path() const override { return reader_.path(); }
  BagFormat format() const override { return BagFormat::kRos1; }
  std::string Describe() const override {
    return reader_.has_index() ? "ROS 1 bag" : "ROS 1 bag (without index)";
  }
  const std::vector<BagConnection>& connections() const override { return connections_; }
  void ReadMessages(const std::function<bool(const BagConnection&)>& wanted,
                    const std::function<void(const BagMessage&)>& visit) override {
    reader_.ReadMessages(
        [&](const RosbagConnection& connection) {
          return wanted(connections_[index_.at(connection.id)]);
        },
        [&](const RosbagMessage& message) {
          BagMessage out;
          out.connection = &connections_[index_.at(message.connection->id)];
          out.time_ns = message.time_ns;
          out.data = message.data;
          out.location = message.location;
          visit(out);
        });
  }

 private:
  RosbagReader reader_;
  std::vector<BagConnection> connections_;
  std::map<uint32_t, size_t> index_;  // ROS 1 connection id -> connections_
};

class Ros1BagWriter : public BagWriter {
 public:
  Ros1BagWriter(const fs::path& path, const RosbagWriterOptions& options)
      : writer_(path, options) {}
  BagFormat format() const override { return BagFormat::kRos1; }
  uint32_t AddTopic(const std::string& topic, BagMessageKind kind) override {
    const RosMessageType& type = BagMessageType(BagFormat::kRos1, kind);
    return writer_.AddConnection(topic, type.name, type.md5sum, type.definition);
  }
  void Write(uint32_t topic_id, timestamp_ns_t time_ns, std::span<const uint8_t> data) override {
    writer_.Write(topic_id, time_ns, data);
  }
  void Close() override { writer_.Close(); }

 private:
  RosbagWriter writer_;
};

// rosbag2's MCAP storage: a schema per type (ros2msg), a channel per topic.
class McapBagWriter : public BagWriter {
 public:
  McapBagWriter(const fs::path& path, const McapWriterOptions& options) : writer_(path, options) {}
  BagFormat format() const override { return BagFormat::kRos2; }
  uint32_t AddTopic(const std::string& topic, BagMessageKind kind) override {
    const RosMessageType& type = BagMessageType(BagFormat::kRos2, kind);
    auto schema = schemas_.find(type.name);
    if (schema == schemas_.end()) {
      schema = schemas_.emplace(type.name, writer_.AddSchema(type.name, "ros2msg", type.definition))
                   .first;
    }
    return writer_.AddChannel(topic, schema->second, "cdr", {{"offered_qos_profiles", ""}});
  }
  void Write(uint32_t topic_id, timestamp_ns_t time_ns, std::span<const uint8_t> data) override {
    writer_.Write(static_cast<uint16_t>(topic_id), time_ns, time_ns, data);
  }
  void Close() override { writer_.Close(); }

 private:
  McapWriter writer_;
  std::map<std::string, uint16_t> schemas_;
};

class SqliteBagWriter : public BagWriter {
 public:
  SqliteBagWriter(const fs::path& path, bool compress_messages)
      : writer_(path, compress_messages) {}
  BagFormat format() const override { return BagFormat::kRos2; }
  uint32_t AddTopic(const std::string& topic, BagMessageKind kind) override {
    return static_cast<uint32_t>(writer_.AddTopic(topic, BagMessageType(BagFormat::kRos2, kind)));
  }
  void Write(uint32_t topic_id, timestamp_ns_t time_ns, std::span<const uint8_t> data) override {
    writer_.Write(topic_id, time_ns, data);
  }
  void Close() override { writer_.Close(); }

 private:
  Rosbag2SqliteWriter writer_;
};

std::string LowerName(const fs::path& path) {
  return ToLower(path.filename().string());
}

enum class Container { kRos1, kSqlite, kMcap, kNone };

Container ContainerOfExtension(const fs::path& path) {
  const std::string name = LowerName(path);
  if (EndsWith(name, ".bag")) return Container::kRos1;
  if (EndsWith(name, ".db3") || EndsWith(name, ".db3.zstd")) return Container::kSqlite;
  if (EndsWith(name, ".mcap") || EndsWith(name, ".mcap.zstd")) return Container::kMcap;
  return Container::kNone;
}

}  // namespace

bool HasBagExtension(const fs::path& path) {
  return ContainerOfExtension(path) != Container::kNone;
}

bool IsBagPath(const fs::path& path) {
  if (HasBagExtension(path)) return true;
  std::error_code error;
  return fs::is_directory(path, error) && fs::is_regular_file(path / "metadata.yaml", error);
}

std::vector<fs::path> BagFiles(const fs::path& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) return Rosbag2FolderFiles(path);
  if (HasBagExtension(path)) return {path};
  return {};
}

std::unique_ptr<BagReader> OpenBag(const fs::path& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) return std::make_unique<Rosbag2Reader>(path);
  if (!fs::is_regular_file(path, error)) throw InputError(path.string(), 0, "bag file not found");
  char start[16] = {};  // enough for each container's magic
  std::ifstream file(path, std::ios::binary);
  file.read(start, sizeof(start));
  const size_t size = static_cast<size_t>(file.gcount());
  if (size >= 9 && std::memcmp(start, kRosbagVersionLine, 9) == 0) {  // "#ROSBAG V"
    return std::make_unique<Ros1BagReader>(path);
  }
  const bool rosbag2_content = (size >= 15 && std::memcmp(start, "SQLite format 3", 15) == 0) ||
                               (size >= 5 && std::memcmp(start, kMcapMagic, 5) == 0) ||
                               (size >= 4 && std::memcmp(start, "\x28\xb5\x2f\xfd", 4) == 0);
  if (rosbag2_content || ContainerOfExtension(path) != Container::kRos1) {
    return std::make_unique<Rosbag2Reader>(path);
  }
  return std::make_unique<Ros1BagReader>(path);  // names what is wrong
}

const RosMessageType& BagMessageType(BagFormat format, BagMessageKind kind) {
  const bool ros1 = format == BagFormat::kRos1;
  switch (kind) {
    case BagMessageKind::kImage: return ros1 ? kRosImageType : kRos2ImageType;
    case BagMessageKind::kCompressedImage:
      return ros1 ? kRosCompressedImageType : kRos2CompressedImageType;
    case BagMessageKind::kImu: return ros1 ? kRosImuType : kRos2ImuType;
    case BagMessageKind::kPoseStamped: return ros1 ? kRosPoseStampedType : kRos2PoseStampedType;
    case BagMessageKind::kString: return ros1 ? kRosStringType : kRos2StringType;
  }
  return ros1 ? kRosStringType : kRos2StringType;
}

BagCompression ParseBagCompression(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "none") return BagCompression::kNone;
  if (lower == "bz2") return BagCompression::kBz2;
  if (lower == "lz4") return BagCompression::kLz4;
  if (lower == "zstd") return BagCompression::kZstd;
  throw InputError("compression '" + name + "': expected none, bz2, lz4 or zstd");
}

std::string BagCompressionName(BagCompression compression) {
  switch (compression) {
    case BagCompression::kDefault: return "default";
    case BagCompression::kNone: return "none";
    case BagCompression::kBz2: return "bz2";
    case BagCompression::kLz4: return "lz4";
    case BagCompression::kZstd: return "zstd";
  }
  return "default";
}

std::string BagWriterOptions::Validate(const fs::path& path) const {
  if (chunk_threshold_bytes == 0) return "chunk_threshold_bytes must be positive";
  const Container container = ContainerOfExtension(path);
  if (container == Container::kNone || EndsWith(LowerName(path), ".zstd")) {
    std::string problem = path.filename().string();
    problem += ": a bag is written as .bag (ROS 1), .db3 or .mcap (ROS 2)";
    return problem;
  }
  const BagCompression c = compression;
  if (c == BagCompression::kDefault || c == BagCompression::kNone) return "";
  if (container == Container::kRos1 && c == BagCompression::kZstd) {
    return "compression zstd: a ROS 1 bag's chunks are none, bz2 or lz4";
  }
  if (container == Container::kMcap && c == BagCompression::kBz2) {
    return "compression bz2: MCAP chunks are none, zstd or lz4";
  }
  if (container == Container::kSqlite && c != BagCompression::kZstd) {
    return "compression " + BagCompressionName(c) +
           ": a rosbag2 sqlite3 bag compresses its messages with zstd, or not at all";
  }
  return "";
}

std::unique_ptr<BagWriter> CreateBagWriter(const fs::path& path, const BagWriterOptions& options) {
  if (const std::string problem = options.Validate(path); !problem.empty()) {
    throw InputError(path.string(), 0, problem);
  }
  switch (ContainerOfExtension(path)) {
    case Container::kRos1: {
      RosbagWriterOptions ros1;
      ros1.chunk_threshold_bytes = options.chunk_threshold_bytes;
      ros1.compression = options.compression == BagCompression::kBz2   ? RosbagCompression::kBz2
                         : options.compression == BagCompression::kLz4 ? RosbagCompression::kLz4
                                                                       : RosbagCompression::kNone;
      return std::make_unique<Ros1BagWriter>(path, ros1);
    }
    case Container::kMcap: {
      McapWriterOptions mcap;
      mcap.chunk_threshold_bytes = options.chunk_threshold_bytes;
      mcap.compression = options.compression == BagCompression::kNone  ? McapCompression::kNone
                         : options.compression == BagCompression::kLz4 ? McapCompression::kLz4
                                                                       : McapCompression::kZstd;
      return std::make_unique<McapBagWriter>(path, mcap);
    }
    case Container::kSqlite:
      return std::make_unique<SqliteBagWriter>(path, options.compression == BagCompression::kZstd);
    case Container::kNone: break;
  }
  throw InputError(path.string(), 0, "not a bag's extension");
}

}  // namespace viosfm

// libFuzzer target: rosbag2's sqlite3 storage (io/rosbag2.h) and the CDR
// messages of known types in it.
//
// The first byte chooses how the rest is used:
//  - odd: the rest is the .db3 file itself (a SQLite file as rosbag2 or
//    viosfm wrote it, or garbage);
//  - even: a database in the early (2019) or current table layout (by the
//    next byte) is created and the rest, read with FuzzedDataProvider, is a
//    list of rows inserted straight through SQLite (topics with any name,
//    type and serialization format; messages with any topic id, timestamp
//    and data, often a CDR message of a known type or a zstd frame; a
//    metadata row with fuzzed YAML), and perhaps a metadata.yaml beside it
//    (read as a bag folder).
// Then the bag is read and every message of a known type decoded.
#include <fuzzer/FuzzedDataProvider.h>
#include <sqlite3.h>

#include "fuzz_ros2_messages.h"
#include "fuzz_util.h"
#include "viosfm/io/compression.h"
#include "viosfm/io/rosbag2.h"

namespace {

namespace fs = std::filesystem;
using namespace viosfm;

constexpr const char* kTypes[] = {"sensor_msgs/msg/Image",
                                  "sensor_msgs/Image",
                                  "sensor_msgs/msg/CompressedImage",
                                  "sensor_msgs/msg/Imu",
                                  "std_msgs/msg/String",
                                  "geometry_msgs/msg/PoseStamped",
                                  "geometry_msgs/msg/TransformStamped",
                                  "test_msgs/msg/Other"};

std::vector<uint8_t> MessageData(FuzzedDataProvider& provider) {
  switch (provider.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: {  // a valid message of a known type, perhaps cut
      RosImu imu;
      imu.header.stamp_ns = provider.ConsumeIntegralInRange<int64_t>(0, int64_t{1} << 40);
      imu.header.frame_id = provider.ConsumeRandomLengthString(12);
      std::vector<uint8_t> bytes = SerializeCdrImu(imu);
      bytes.resize(provider.ConsumeIntegralInRange<size_t>(0, bytes.size()));
      return bytes;
    }
    case 1: {
      RosImage image;
      image.width = provider.ConsumeIntegralInRange<uint32_t>(0, 8);
      image.height = provider.ConsumeIntegralInRange<uint32_t>(0, 8);
      image.step = provider.ConsumeIntegralInRange<uint32_t>(0, 32);
      image.encoding = provider.PickValueInArray({"mono8", "bgr8", "rgb8", "16UC1"});
      image.data = provider.ConsumeBytes<uint8_t>(provider.ConsumeIntegralInRange<size_t>(0, 64));
      std::vector<uint8_t> bytes = SerializeCdrImage(image);
      if (provider.ConsumeBool()) return CompressZstd(bytes, 1);
      return bytes;
    }
    case 2:
      return CompressZstd(
          provider.ConsumeBytes<uint8_t>(provider.ConsumeIntegralInRange<size_t>(0, 256)), 1);
    default: return provider.ConsumeBytes<uint8_t>(provider.ConsumeIntegralInRange<size_t>(0, 512));
  }
}

void CreateBag(const fs::path& path, FuzzedDataProvider& provider) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    sqlite3_close_v2(db);
    return;
  }
  const bool current = provider.ConsumeBool();
  sqlite3_exec(db,
               current ? "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT);"
                         "INSERT INTO schema VALUES(4,'jazzy');"
                         "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER,"
                         "metadata TEXT);"
                         "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT,type TEXT,"
                         "serialization_format TEXT,offered_qos_profiles TEXT,"
                         "type_description_hash TEXT);"
                         "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER,"
                         "timestamp INTEGER,data BLOB);"
                       : "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT,type TEXT,"
                         "serialization_format TEXT);"
                         "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER,"
                         "timestamp INTEGER,data BLOB);",
               nullptr, nullptr, nullptr);
  sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr);
  for (int row = 0; row < 48 && provider.remaining_bytes() > 0; ++row) {
    sqlite3_stmt* statement = nullptr;
    const int kind = provider.ConsumeIntegralInRange<int>(0, 5);
    if (kind == 0) {
      sqlite3_prepare_v2(db,
                         "INSERT OR REPLACE INTO topics(id, name, type, serialization_format) "
                         "VALUES(?, ?, ?, ?)",
                         -1, &statement, nullptr);
      if (statement == nullptr) continue;
      sqlite3_bind_int64(statement, 1, provider.ConsumeIntegralInRange<int64_t>(-1, 4));
      const std::string name = provider.ConsumeRandomLengthString(16);
      sqlite3_bind_text(statement, 2, name.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(statement, 3, provider.PickValueInArray(kTypes), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(statement, 4, provider.ConsumeBool() ? "cdr" : "json", -1,
                        SQLITE_TRANSIENT);
    } else if (kind == 1 && current) {
      sqlite3_prepare_v2(db, "INSERT INTO metadata(metadata_version, metadata) VALUES(7, ?)", -1,
                         &statement, nullptr);
      if (statement == nullptr) continue;
      const std::string yaml =
          "storage_identifier: sqlite3\ncompression_format: " +
          std::string(provider.ConsumeBool() ? "zstd" : "\"\"") + "\ncompression_mode: " +
          provider.PickValueInArray({"MESSAGE", "FILE", "NONE", "\"\"", "[1"}) + "\n" +
          provider.ConsumeRandomLengthString(32);
      sqlite3_bind_text(statement, 1, yaml.c_str(), -1, SQLITE_TRANSIENT);
    } else {
      sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)", -1,
                         &statement, nullptr);
      if (statement == nullptr) continue;
      sqlite3_bind_int64(statement, 1, provider.ConsumeIntegralInRange<int64_t>(-1, 4));
      sqlite3_bind_int64(statement, 2, provider.ConsumeIntegral<int64_t>());
      const std::vector<uint8_t> data = MessageData(provider);
      if (provider.ConsumeIntegralInRange<int>(0, 15) == 0) {
        sqlite3_bind_null(statement, 3);
      } else {
        sqlite3_bind_blob(statement, 3, data.data(), static_cast<int>(data.size()),
                          SQLITE_TRANSIENT);
      }
    }
    sqlite3_step(statement);  // constraint violations are fine
    sqlite3_finalize(statement);
  }
  sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
  sqlite3_close_v2(db);
}

void ReadBag(const fs::path& path) {
  viosfm::fuzz::AcceptsInput([&] {
    Rosbag2Reader reader(path);
    reader.ReadMessages(
        [](const BagConnection&) { return true; },
        [&](const BagMessage& message) {
          viosfm::fuzz::Require(message.connection != nullptr, "a message has a topic");
          viosfm::fuzz::ReadCdrMessage(message.connection->type, message.data, message.location);
        });
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace viosfm::fuzz;
  if (size == 0) return 0;
  const fs::path folder = ScratchFolder() / "bag";
  std::error_code ignored;
  fs::remove_all(folder, ignored);
  fs::create_directories(folder);
  const fs::path path = folder / "bag_0.db3";
  if (data[0] % 2 == 1) {
    // A zstd file would be read as a per-file-compressed bag: decompressed
    // to a file, which a fuzzer's tiny input can make gigabytes long.
    if (StartsWithZstdFrame(std::span<const uint8_t>(data + 1, size - 1))) return 0;
    WriteBytes(path, AsText(data + 1, size - 1));
    ReadBag(path);
    return 0;
  }
  FuzzedDataProvider provider(data + 1, size - 1);
  CreateBag(path, provider);
  if (provider.ConsumeBool()) {
    WriteBytes(folder / "metadata.yaml",
               "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
               "  relative_file_paths: [bag_0.db3]\n  compression_format: " +
                   std::string(provider.ConsumeBool() ? "zstd" : "''") + "\n  compression_mode: " +
                   provider.PickValueInArray<std::string>({"MESSAGE", "FILE", "NONE", "''"}) +
                   "\n" + provider.ConsumeRemainingBytesAsString());
    ReadBag(folder);
  } else {
    ReadBag(path);
  }
  return 0;
}

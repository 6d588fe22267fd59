#include "viosfm/io/rosbag2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "viosfm/io/compression.h"
#include "viosfm/io/ros_messages.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

const BagConnection* Find(const BagReader& reader, const std::string& topic) {
  for (const BagConnection& connection : reader.connections()) {
    if (connection.topic == topic) return &connection;
  }
  return nullptr;
}

// The messages of one topic, decompressed as the bag says.
std::vector<std::vector<uint8_t>> MessagesOf(BagReader& reader, const std::string& topic,
                                             std::vector<timestamp_ns_t>* times = nullptr) {
  std::vector<std::vector<uint8_t>> out;
  reader.ReadMessages([&](const BagConnection& c) { return c.topic == topic; },
                      [&](const BagMessage& message) {
                        out.emplace_back(message.data.begin(), message.data.end());
                        if (times) times->push_back(message.time_ns);
                      });
  return out;
}

// The per-topic message counts of a bag's metadata.yaml (written by rosbag2).
std::map<std::string, uint64_t> CountsOfMetadata(const fs::path& yaml) {
  std::map<std::string, uint64_t> counts;
  for (const Rosbag2Metadata::Topic& topic :
       ParseRosbag2Metadata(ReadTextFile(yaml), yaml.string()).topics) {
    counts[topic.name] = topic.message_count;
  }
  return counts;
}

// The sensor messages of the shared bags, against the values their README
// gives: the early 2019 sqlite3 layout (rosbag2.js's sample).
TEST(Rosbag2, ReadsTheEarlySqliteLayout) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  const fs::path path = root / "image_imu" / "rosbag2js_sample.db3";
  Rosbag2Reader reader(path);
  EXPECT_EQ(reader.storage(), Rosbag2Storage::kSqlite3);
  EXPECT_EQ(reader.compression(), Rosbag2Compression::kNone);
  ASSERT_NE(Find(reader, "/image"), nullptr);
  EXPECT_EQ(Find(reader, "/image")->type, "sensor_msgs/Image");
  EXPECT_EQ(Find(reader, "/image")->serialization, "cdr");
  EXPECT_EQ(Find(reader, "/imu")->num_messages, 1u);

  const auto images = MessagesOf(reader, "/image");
  ASSERT_EQ(images.size(), 1u);
  const RosImage image = DeserializeCdrImage(images[0], "image");
  EXPECT_EQ(image.width, 640u);
  EXPECT_EQ(image.height, 480u);
  EXPECT_EQ(image.encoding, "bgr8");
  EXPECT_EQ(image.header.stamp_ns, 0);
  EXPECT_EQ(image.data.size(), 640u * 480u * 3u);

  const auto compressed = MessagesOf(reader, "/image/compressed");
  ASSERT_EQ(compressed.size(), 1u);
  const RosCompressedImage jpeg = DeserializeCdrCompressedImage(compressed[0], "compressed");
  EXPECT_EQ(jpeg.format, "bgr8; jpeg compressed bgr8");
  EXPECT_EQ(jpeg.data.size(), 73470u);

  const auto imus = MessagesOf(reader, "/imu");
  ASSERT_EQ(imus.size(), 1u);
  const RosImu imu = DeserializeCdrImu(imus[0], "imu");
  EXPECT_EQ(imu.header.stamp_ns, 1553411909072940288);
  EXPECT_EQ(imu.header.frame_id, "base_imu_link");
  EXPECT_NEAR(imu.orientation.x(), -0.003037, 5e-7);
  EXPECT_NEAR(imu.orientation.y(), -0.821770, 5e-7);
  EXPECT_NEAR(imu.orientation.z(), 0.569726, 5e-7);
  EXPECT_NEAR(imu.orientation.w(), -0.009894, 5e-7);
  EXPECT_EQ(imu.angular_velocity, Eigen::Vector3d::Zero());
  EXPECT_EQ(imu.linear_acceleration, Eigen::Vector3d::Zero());
}

// The same three message types in an MCAP file written by libmcap (rerun's
// test asset).
TEST(Rosbag2, ReadsSensorMessagesFromMcap) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  Rosbag2Reader reader(root / "image_imu" / "rerun_sensors.mcap");
  EXPECT_EQ(reader.storage(), Rosbag2Storage::kMcap);
  uint64_t total = 0;
  for (const BagConnection& connection : reader.connections()) total += connection.num_messages;
  EXPECT_EQ(total, 194u);

  const auto images = MessagesOf(reader, "/image");
  ASSERT_EQ(images.size(), 1u);
  const RosImage image = DeserializeCdrImage(images[0], "image");
  EXPECT_EQ(image.width, 640u);
  EXPECT_EQ(image.height, 480u);
  EXPECT_EQ(image.encoding, "rgb8");
  EXPECT_EQ(image.step, 1920u);
  EXPECT_EQ(image.header.stamp_ns, 1757502238482648699);
  EXPECT_EQ(image.header.frame_id, "base_link");

  const auto compressed = MessagesOf(reader, "/compressed_image");
  ASSERT_EQ(compressed.size(), 1u);
  const RosCompressedImage jpeg = DeserializeCdrCompressedImage(compressed[0], "compressed");
  EXPECT_EQ(jpeg.format, "jpeg");
  EXPECT_EQ(jpeg.data.size(), 361069u);

  const auto imus = MessagesOf(reader, "/imu");
  ASSERT_EQ(imus.size(), 1u);
  const RosImu imu = DeserializeCdrImu(imus[0], "imu");
  EXPECT_EQ(imu.header.stamp_ns, 1757502238482648699);
  EXPECT_EQ(imu.angular_velocity, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(imu.linear_acceleration, Eigen::Vector3d(0, 0, 9.81));
}

// rosbag2's own test bags: the counts their metadata.yaml states, split
// bags, the current sqlite3 layout, compressed messages.
TEST(Rosbag2, ReadsTheFormatCasesOfRosbag2) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  const fs::path format = root / "format";
  {
    SCOPED_TRACE("talker_db3");
    Rosbag2Reader reader(format / "talker_db3" / "multiple_files_0.db3");
    const auto messages = MessagesOf(reader, "/chatter");
    ASSERT_EQ(messages.size(), 1324u);
    EXPECT_EQ(DeserializeCdrString(messages.front(), "first"), "test");
    EXPECT_EQ(DeserializeCdrString(messages.back(), "last"), "test");
  }
  for (const char* name : {"talker_mcap", "wbag_split_mcap", "cdr_test_db3"}) {
    SCOPED_TRACE(name);
    const fs::path folder = format / name;
    Rosbag2Reader reader(folder);
    const std::map<std::string, uint64_t> expected = CountsOfMetadata(folder / "metadata.yaml");
    std::map<std::string, uint64_t> counted;
    for (const auto& [topic, count] : expected) {
      ASSERT_NE(Find(reader, topic), nullptr) << topic;
      EXPECT_EQ(Find(reader, topic)->num_messages, count) << topic;
      counted[topic] = MessagesOf(reader, topic).size();
    }
    EXPECT_EQ(counted, expected);
  }
  {
    SCOPED_TRACE("wbag_split_mcap");
    Rosbag2Reader reader(format / "wbag_split_mcap");
    EXPECT_EQ(reader.files().size(), 5u);
    uint64_t total = 0;
    reader.ReadMessages([](const BagConnection&) { return true; },
                        [&](const BagMessage& message) {
                          DeserializeCdrString(message.data, message.location);
                          ++total;
                        });
    EXPECT_EQ(total, 6074u);
  }
  {
    SCOPED_TRACE("talker_mcap");
    Rosbag2Reader reader(format / "talker_mcap");
    const auto messages = MessagesOf(reader, "/topic");
    ASSERT_EQ(messages.size(), 10u);
    EXPECT_EQ(DeserializeCdrString(messages[9], "m"), "Hello, world! 9");
  }
  {
    SCOPED_TRACE("cdr_test_db3: the current layout");
    Rosbag2SqliteFile file(format / "cdr_test_db3" / "cdr_test_0.db3");
    EXPECT_EQ(file.schema_version(), 4);
    ASSERT_TRUE(file.metadata().has_value());
    EXPECT_EQ(file.metadata()->message_count, 7u);
    EXPECT_EQ(file.metadata()->storage_identifier, "sqlite3");
  }
  {
    SCOPED_TRACE("message_compression_db3: zstd per message, no metadata.yaml");
    Rosbag2Reader reader(format / "message_compression_db3" / "message_compression_0.db3");
    std::vector<timestamp_ns_t> times;
    const auto messages = MessagesOf(reader, "/topic", &times);
    ASSERT_EQ(messages.size(), 120u);
    for (size_t i = 0; i < messages.size(); ++i) {
      const std::string text = DeserializeCdrString(messages[i], "m");
      EXPECT_TRUE(text.starts_with("Hello, world! ")) << text;
      if (i > 0) {
        EXPECT_GT(times[i], times[i - 1]);
      }
    }
    EXPECT_EQ(MessagesOf(reader, "/rosout").size(), 260u);
  }
}

TEST(Rosbag2, RefusesBagsItCannotReadWithClearErrors) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  const fs::path wrong_rmw = root / "format" / "wrong_rmw_mcap";
  const std::string rmw = testing::InputErrorMessage([&] { Rosbag2Reader reader(wrong_rmw); });
  EXPECT_NE(rmw.find(wrong_rmw.string()), std::string::npos) << rmw;
  EXPECT_NE(rmw.find("no topic is serialized as CDR (the bag states 'wrong_format')"),
            std::string::npos)
      << rmw;

  // Labelled sensor_msgs/msg/Imu, 84-byte messages of another layout.
  const fs::path imu = root / "broken" / "ros2_imu.mcap";
  Rosbag2Reader reader(imu);
  const BagConnection* connection = Find(reader, "/vehicle/imu/data_raw");
  ASSERT_NE(connection, nullptr);
  EXPECT_EQ(connection->num_messages, 3u);
  int refused = 0;
  reader.ReadMessages([](const BagConnection&) { return true; },
                      [&](const BagMessage& message) {
                        EXPECT_EQ(message.data.size(), 84u);
                        const std::string error = testing::InputErrorMessage([&] {
                          DeserializeCdrImu(message.data, imu.string() + ": " + message.location);
                        });
                        EXPECT_NE(error.find(imu.string()), std::string::npos) << error;
                        EXPECT_NE(error.find("sensor_msgs/msg/Imu"), std::string::npos) << error;
                        ++refused;
                      });
  EXPECT_EQ(refused, 3);
}

// A folder whose metadata.yaml lists a missing file, a folder without
// metadata.yaml, a file that is neither SQLite nor MCAP.
TEST(Rosbag2, BadBagsNameTheFile) {
  const fs::path folder = testing::MakeScratchFolder("rosbag2_bad");
  fs::create_directories(folder / "empty");
  EXPECT_NE(testing::InputErrorMessage([&] {
              Rosbag2Reader reader(folder / "empty");
            }).find("a folder without metadata.yaml"),
            std::string::npos);
  fs::create_directories(folder / "missing");
  testing::WriteTextFile(folder / "missing" / "metadata.yaml",
                         "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: "
                         "sqlite3\n  relative_file_paths:\n    - missing_0.db3\n");
  const std::string missing =
      testing::InputErrorMessage([&] { Rosbag2Reader reader(folder / "missing"); });
  EXPECT_NE(missing.find("metadata.yaml: relative_file_paths lists 'missing_0.db3'"),
            std::string::npos)
      << missing;
  testing::WriteTextFile(folder / "text.db3", "this is not a database, just text of some length");
  const std::string text =
      testing::InputErrorMessage([&] { Rosbag2Reader reader(folder / "text.db3"); });
  EXPECT_NE(text.find("neither an SQLite database"), std::string::npos) << text;
  fs::create_directories(folder / "yaml");
  testing::WriteTextFile(folder / "yaml" / "metadata.yaml", "rosbag2_bagfile_information: [1, 2");
  EXPECT_NE(testing::InputErrorMessage([&] {
              Rosbag2Reader reader(folder / "yaml");
            }).find("metadata.yaml: not valid YAML"),
            std::string::npos);
}

// viosfm's sqlite3 writer, read back: one file, split over a folder with
// metadata.yaml, compressed per message and per file (zstd).
TEST(Rosbag2, WrittenSqliteBagsReadBackInEveryForm) {
  const fs::path folder = testing::MakeScratchFolder("rosbag2_sqlite");
  const auto write = [&](const fs::path& path, bool compress, int first, int count) {
    Rosbag2SqliteWriter writer(path, compress);
    const int64_t strings = writer.AddTopic("/text", kRos2StringType);
    const int64_t imus = writer.AddTopic("/imu", kRos2ImuType);
    for (int i = first; i < first + count; ++i) {
      writer.Write(strings, 1000 * i, SerializeCdrString("text " + std::to_string(i)));
      RosImu imu;
      imu.header.stamp_ns = 1000 * i + 1;
      imu.angular_velocity = Eigen::Vector3d(i, -i, 0.5);
      writer.Write(imus, 1000 * i + 1, SerializeCdrImu(imu));
    }
    writer.Close();
  };
  const auto check = [&](const fs::path& path, int count, Rosbag2Compression compression) {
    Rosbag2Reader reader(path);
    EXPECT_EQ(reader.compression(), compression);
    EXPECT_EQ(Find(reader, "/text")->type, "std_msgs/msg/String");
    EXPECT_EQ(Find(reader, "/text")->num_messages, static_cast<uint64_t>(count));
    const auto texts = MessagesOf(reader, "/text");
    const auto imus = MessagesOf(reader, "/imu");
    ASSERT_EQ(texts.size(), static_cast<size_t>(count));
    ASSERT_EQ(imus.size(), static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) {
      EXPECT_EQ(DeserializeCdrString(texts[i], "t"), "text " + std::to_string(i));
      EXPECT_EQ(DeserializeCdrImu(imus[i], "i").angular_velocity.x(), i);
    }
  };
  write(folder / "one.db3", false, 0, 20);
  check(folder / "one.db3", 20, Rosbag2Compression::kNone);
  {
    Rosbag2SqliteFile file(folder / "one.db3");
    EXPECT_EQ(file.schema_version(), 4);
    ASSERT_TRUE(file.metadata().has_value());
    EXPECT_EQ(file.metadata()->message_count, 40u);
  }
  write(folder / "message.db3", true, 0, 20);
  check(folder / "message.db3", 20, Rosbag2Compression::kMessage);

  // Split: two files and a metadata.yaml listing them.
  fs::create_directories(folder / "split");
  write(folder / "split" / "split_0.db3", false, 0, 12);
  write(folder / "split" / "split_1.db3", false, 12, 8);
  Rosbag2Metadata metadata;
  metadata.version = 5;
  metadata.storage_identifier = "sqlite3";
  metadata.relative_file_paths = {"split_0.db3", "split_1.db3"};
  testing::WriteTextFile(folder / "split" / "metadata.yaml", Rosbag2MetadataYaml(metadata));
  check(folder / "split", 20, Rosbag2Compression::kNone);
  EXPECT_EQ(Rosbag2FolderFiles(folder / "split").size(), 3u);

  // Per file: each .db3 zstd-compressed, as rosbag2's FILE mode leaves them.
  fs::create_directories(folder / "file");
  CompressZstdFile(folder / "one.db3", folder / "file" / "file_0.db3.zstd");
  metadata.relative_file_paths = {"file_0.db3.zstd"};
  metadata.compression_format = "zstd";
  metadata.compression_mode = "FILE";
  testing::WriteTextFile(folder / "file" / "metadata.yaml", Rosbag2MetadataYaml(metadata));
  check(folder / "file", 20, Rosbag2Compression::kFile);
  fs::path decompressed;
  {
    Rosbag2Reader reader(folder / "file");
    decompressed = reader.files().front();
    EXPECT_TRUE(fs::is_regular_file(decompressed));
    EXPECT_EQ(ReadTextFile(decompressed), ReadTextFile(folder / "one.db3"));
  }
  EXPECT_FALSE(fs::exists(decompressed)) << "the decompressed copy is removed";

  // A file given alone that metadata.yaml lists with others is read alone.
  Rosbag2Reader alone(folder / "split" / "split_1.db3");
  EXPECT_EQ(MessagesOf(alone, "/text").size(), 8u);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/mcap.h"

#include <gtest/gtest.h>

#include <fstream>

#include "viosfm/io/ros_messages.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

struct ReadBack {
  std::string topic;
  timestamp_ns_t log_time_ns = 0;
  timestamp_ns_t publish_time_ns = 0;
  uint32_t sequence = 0;
  std::vector<uint8_t> data;
};

std::vector<ReadBack> ReadAll(McapReader& reader) {
  std::vector<ReadBack> out;
  reader.ReadMessages(
      [](const McapChannel&) { return true; },
      [&](const McapMessage& message) {
        out.push_back({message.channel->topic, message.log_time_ns, message.publish_time_ns,
                       message.sequence,
                       std::vector<uint8_t>(message.data.begin(), message.data.end())});
      });
  return out;
}

const McapChannel* FindChannel(const McapReader& reader, const std::string& topic) {
  for (const McapChannel& channel : reader.channels()) {
    if (channel.topic == topic) return &channel;
  }
  return nullptr;
}

void WriteFileBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::string Bytes(const fs::path& path) {
  return ReadTextFile(path);
}

// CRC-32 check values of the zlib polynomial.
TEST(Mcap, Crc32MatchesTheStandardCheckValue) {
  const std::string text = "123456789";
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  EXPECT_EQ(Crc32(bytes), 0xcbf43926u);
  EXPECT_EQ(Crc32(bytes.subspan(4), Crc32(bytes.subspan(0, 4))), 0xcbf43926u);
  EXPECT_EQ(Crc32({}), 0u);
}

// Files written from the specification by another program
// (testdata/make_mcap_fixtures.py: Python, the lz4 command): lz4 chunks
// without a summary, and messages outside chunks with a summary. Both
// hold the same messages, one of them big-endian CDR.
TEST(Mcap, ReadsFilesWrittenFromTheSpecificationElsewhere) {
  for (const char* name : {"mcap_lz4_no_summary.mcap", "mcap_unchunked_summary.mcap"}) {
    SCOPED_TRACE(name);
    McapReader reader(testing::SourcePath(std::string("io/testdata/") + name));
    EXPECT_EQ(reader.profile(), "ros2");
    EXPECT_EQ(reader.has_summary(), std::string(name) == "mcap_unchunked_summary.mcap");
    ASSERT_EQ(reader.channels().size(), 2u);
    const McapChannel* chatter = FindChannel(reader, "/chatter");
    const McapChannel* imu = FindChannel(reader, "/imu");
    ASSERT_TRUE(chatter != nullptr && imu != nullptr);
    EXPECT_EQ(chatter->num_messages, 3u);
    EXPECT_EQ(imu->num_messages, 1u);
    EXPECT_EQ(chatter->schema_name, "std_msgs/msg/String");
    EXPECT_EQ(chatter->schema_encoding, "ros2msg");
    EXPECT_EQ(chatter->message_encoding, "cdr");
    EXPECT_EQ(imu->schema_name, "sensor_msgs/msg/Imu");
    EXPECT_EQ(chatter->metadata.at("offered_qos_profiles"), "");
    const std::vector<ReadBack> messages = ReadAll(reader);
    ASSERT_EQ(messages.size(), 4u);
    EXPECT_EQ(DeserializeCdrString(messages[0].data, "m0"), "one");
    EXPECT_EQ(DeserializeCdrString(messages[1].data, "m1"), "two");
    EXPECT_EQ(DeserializeCdrString(messages[3].data, "m3"), "three");
    EXPECT_EQ(messages[0].log_time_ns, 100);
    EXPECT_EQ(messages[3].log_time_ns, 300);
    EXPECT_EQ(messages[3].sequence, 2u);
    ASSERT_EQ(messages[2].topic, "/imu");
    EXPECT_EQ(messages[2].log_time_ns, 250);
    const RosImu imu_message = DeserializeCdrImu(messages[2].data, "m2");
    EXPECT_EQ(imu_message.header.stamp_ns, 1553411909072940288);
    EXPECT_EQ(imu_message.header.frame_id, "imu_link");
    EXPECT_EQ(imu_message.orientation.coeffs(), Eigen::Vector4d(0.1, -0.2, 0.3, 0.9));
    EXPECT_EQ(imu_message.angular_velocity, Eigen::Vector3d(0.5, -0.25, 0.125));
    EXPECT_EQ(imu_message.linear_acceleration, Eigen::Vector3d(0.01, -0.02, 9.81));
    EXPECT_EQ(imu_message.orientation_covariance(0, 0), -1.0);
    EXPECT_EQ(imu_message.linear_acceleration_covariance(0, 0), -1.0);
  }
}

// What viosfm writes it reads back, in every chunk compression, with and
// without a summary: channels, schemas, counts, times, sequence numbers and
// bytes.
TEST(Mcap, WriterRoundTripsInEveryCompression) {
  const fs::path folder = testing::MakeScratchFolder("mcap_roundtrip");
  for (const McapCompression compression :
       {McapCompression::kNone, McapCompression::kZstd, McapCompression::kLz4}) {
    for (const bool summary : {true, false}) {
      SCOPED_TRACE(McapCompressionName(compression) + (summary ? " summary" : " no summary"));
      const fs::path path =
          folder / ("rt_" + McapCompressionName(compression) + (summary ? "_s" : "_n") + ".mcap");
      McapWriterOptions options;
      options.compression = compression;
      options.summary = summary;
      options.chunk_threshold_bytes = 300;  // several chunks
      std::vector<std::pair<std::string, std::vector<uint8_t>>> written;
      {
        McapWriter writer(path, options);
        const uint16_t schema = writer.AddSchema("std_msgs/msg/String", "ros2msg", "string data\n");
        const uint16_t a = writer.AddChannel("/a", schema, "cdr", {{"offered_qos_profiles", ""}});
        const uint16_t b = writer.AddChannel("/b", schema, "cdr", {});
        for (int i = 0; i < 40; ++i) {
          std::vector<uint8_t> data = SerializeCdrString(std::string(i, 'x') + std::to_string(i));
          writer.Write(i % 3 == 0 ? b : a, 1000 + i, 2000 + i, data);
          written.push_back({i % 3 == 0 ? "/b" : "/a", data});
        }
        writer.Close();
      }
      McapReader reader(path);
      EXPECT_EQ(reader.has_summary(), summary);
      ASSERT_EQ(reader.channels().size(), 2u);
      EXPECT_EQ(FindChannel(reader, "/a")->num_messages, 26u);
      EXPECT_EQ(FindChannel(reader, "/b")->num_messages, 14u);
      EXPECT_EQ(FindChannel(reader, "/b")->schema_data, "string data\n");
      const std::vector<ReadBack> messages = ReadAll(reader);
      ASSERT_EQ(messages.size(), written.size());
      uint32_t sequence_a = 0;
      for (size_t i = 0; i < messages.size(); ++i) {
        EXPECT_EQ(messages[i].topic, written[i].first);
        EXPECT_EQ(messages[i].data, written[i].second);
        EXPECT_EQ(messages[i].log_time_ns, 1000 + static_cast<timestamp_ns_t>(i));
        EXPECT_EQ(messages[i].publish_time_ns, 2000 + static_cast<timestamp_ns_t>(i));
        if (messages[i].topic == "/a") {
          EXPECT_EQ(messages[i].sequence, sequence_a++);
        }
      }
    }
  }
}

// The rosbag2 test bags (written by rosbag2 and libmcap): zstd chunks, a
// summary, counts as their metadata.yaml states them.
TEST(Mcap, ReadsBagsWrittenByRosbag2) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  McapReader talker(root / "format" / "talker_mcap" / "talker.mcap");
  EXPECT_EQ(talker.profile(), "ros2");
  EXPECT_EQ(FindChannel(talker, "/topic")->num_messages, 10u);
  EXPECT_EQ(FindChannel(talker, "/rosout")->num_messages, 10u);
  EXPECT_EQ(FindChannel(talker, "/parameter_events")->num_messages, 0u);
  std::vector<std::string> strings;
  talker.ReadMessages([](const McapChannel& channel) { return channel.topic == "/topic"; },
                      [&](const McapMessage& message) {
                        strings.push_back(DeserializeCdrString(message.data, "talker"));
                      });
  ASSERT_EQ(strings.size(), 10u);
  for (size_t i = 0; i < strings.size(); ++i) {
    EXPECT_EQ(strings[i], "Hello, world! " + std::to_string(i));
  }

  McapReader evo(root / "format" / "evo_nav2_turtlebot_zstd.mcap");
  EXPECT_EQ(FindChannel(evo, "/odom")->num_messages, 2639u);
  EXPECT_EQ(FindChannel(evo, "/odom")->schema_name, "nav_msgs/msg/Odometry");
  EXPECT_EQ(FindChannel(evo, "/tf")->num_messages, 5422u);
  uint64_t read = 0;
  evo.ReadMessages([](const McapChannel& channel) { return channel.topic == "/odom"; },
                   [&](const McapMessage&) { ++read; });
  EXPECT_EQ(read, 2639u);
}

// The broken files of the test data: a clear error naming the file and the
// place, never a crash or an empty result.
TEST(Mcap, BrokenFilesGiveClearErrors) {
  VIOSFM_REQUIRE_DATASET(root, "ros2_bags");
  const fs::path crc = root / "broken" / "crc_corrupt.mcap";
  const std::string crc_error = testing::InputErrorMessage([&] {
    McapReader reader(crc);
    ReadAll(reader);
  });
  EXPECT_NE(crc_error.find(crc.string()), std::string::npos) << crc_error;
  EXPECT_NE(crc_error.find("byte offset 2547: chunk record: the records' CRC is"),
            std::string::npos)
      << crc_error;

  const fs::path truncated = root / "broken" / "truncated.mcap";
  const std::string truncated_error =
      testing::InputErrorMessage([&] { McapReader reader(truncated); });
  EXPECT_NE(truncated_error.find(truncated.string()), std::string::npos) << truncated_error;
  EXPECT_NE(truncated_error.find("byte offset 2335: chunk record of"), std::string::npos)
      << truncated_error;
  EXPECT_NE(truncated_error.find("truncated"), std::string::npos) << truncated_error;
}

// Damaged copies of a file viosfm wrote: each is refused with what is wrong.
TEST(Mcap, DamagedFilesNameWhatIsWrong) {
  const fs::path folder = testing::MakeScratchFolder("mcap_damaged");
  const fs::path good = folder / "good.mcap";
  {
    McapWriterOptions options;
    options.compression = McapCompression::kZstd;
    McapWriter writer(good, options);
    const uint16_t schema = writer.AddSchema("std_msgs/msg/String", "ros2msg", "string data\n");
    const uint16_t channel = writer.AddChannel("/a", schema, "cdr", {});
    for (int i = 0; i < 50; ++i)
      writer.Write(channel, i, i, SerializeCdrString("message " + std::to_string(i)));
    writer.Close();
  }
  const std::string bytes = Bytes(good);
  const auto error_of = [&](const std::string& name, const std::string& content) {
    WriteFileBytes(folder / name, content);
    return testing::InputErrorMessage([&] {
      McapReader reader(folder / name);
      ReadAll(reader);
    });
  };
  // Not MCAP at all; another major version.
  EXPECT_NE(error_of("text.mcap", "hello").find("not an MCAP file"), std::string::npos);
  std::string v1 = bytes;
  v1[5] = '1';
  EXPECT_NE(error_of("v1.mcap", v1).find("major version '1'"), std::string::npos);
  // Cut anywhere: truncated.
  for (const size_t size : {size_t{12}, size_t{60}, bytes.size() / 2, bytes.size() - 3}) {
    const std::string error = error_of("cut.mcap", bytes.substr(0, size));
    EXPECT_NE(error.find("truncated"), std::string::npos) << size << ": " << error;
  }
  // A flipped byte in the compressed chunk: zstd or the CRC notices.
  std::string flipped = bytes;
  flipped[120] = static_cast<char>(flipped[120] ^ 0x5a);
  const std::string flipped_error = error_of("flipped.mcap", flipped);
  EXPECT_TRUE(flipped_error.find("zstd") != std::string::npos ||
              flipped_error.find("CRC") != std::string::npos)
      << flipped_error;
  // A flipped byte in the summary: its CRC.
  std::string summary = bytes;
  summary[bytes.size() - 60] = static_cast<char>(summary[bytes.size() - 60] ^ 1);
  EXPECT_NE(error_of("summary.mcap", summary).find("summary section"), std::string::npos);
}

TEST(Mcap, UnclosedWriterLeavesNoFile) {
  const fs::path folder = testing::MakeScratchFolder("mcap_unclosed");
  {
    McapWriter writer(folder / "x.mcap");
    writer.AddChannel("/a", 0, "cdr", {});
  }
  EXPECT_TRUE(fs::is_empty(folder));
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/rosbag.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstring>
#include <fstream>
#include <map>

#include "viosfm/io/ros_messages.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

using Bytes = std::vector<uint8_t>;

struct ReadMessage {
  std::string topic;
  timestamp_ns_t time_ns;
  Bytes data;
};

std::vector<ReadMessage> ReadAll(const fs::path& path) {
  RosbagReader reader(path);
  std::vector<ReadMessage> messages;
  reader.ReadMessages(
      [](const RosbagConnection&) { return true; },
      [&](const RosbagMessage& m) {
        messages.push_back({m.connection->topic, m.time_ns, Bytes(m.data.begin(), m.data.end())});
      });
  return messages;
}

std::string ReadFileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteFileBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The three bags ROS's librosbag_storage wrote (testdata/README.md lists
// their content): every message must come out with ROS's values, and our
// serializer must reproduce ROS's bytes exactly.
TEST(Rosbag, ReadsBagsWrittenByRosInEveryCompression) {
  for (const std::string compression : {"none", "bz2", "lz4"}) {
    SCOPED_TRACE(compression);
    const fs::path path = testing::SourcePath("io/testdata/librosbag_" + compression + ".bag");
    RosbagReader reader(path);
    EXPECT_TRUE(reader.has_index());
    std::map<std::string, const RosbagConnection*> by_topic;
    for (const RosbagConnection& c : reader.connections()) by_topic[c.topic] = &c;
    ASSERT_EQ(by_topic.size(), 4u);
    EXPECT_EQ(by_topic["/imu0"]->type, "sensor_msgs/Imu");
    EXPECT_EQ(by_topic["/imu0"]->md5sum, kRosImuType.md5sum);
    EXPECT_EQ(by_topic["/imu0"]->num_messages, 5u);
    EXPECT_EQ(by_topic["/cam0/image_raw"]->md5sum, kRosImageType.md5sum);
    EXPECT_EQ(by_topic["/cam0/image_raw"]->num_messages, 3u);
    EXPECT_EQ(by_topic["/groundtruth/pose"]->md5sum, kRosPoseStampedType.md5sum);
    EXPECT_EQ(by_topic["/note"]->md5sum, kRosStringType.md5sum);

    std::vector<RosImu> imu;
    std::vector<RosImage> images;
    std::vector<RosPoseStamped> poses;
    std::vector<std::string> notes;
    reader.ReadMessages([](const RosbagConnection&) { return true; },
                        [&](const RosbagMessage& m) {
                          const std::string& type = m.connection->type;
                          const Bytes bytes(m.data.begin(), m.data.end());
                          if (type == kRosImuType.name) {
                            imu.push_back(DeserializeRosImu(m.data, m.location));
                            EXPECT_EQ(SerializeRosImu(imu.back()), bytes);
                            EXPECT_EQ(m.time_ns, imu.back().header.stamp_ns);
                          } else if (type == kRosImageType.name) {
                            images.push_back(DeserializeRosImage(m.data, m.location));
                            EXPECT_EQ(SerializeRosImage(images.back()), bytes);
                          } else if (type == kRosPoseStampedType.name) {
                            poses.push_back(DeserializeRosPoseStamped(m.data, m.location));
                            EXPECT_EQ(SerializeRosPoseStamped(poses.back()), bytes);
                          } else if (type == kRosStringType.name) {
                            notes.push_back(DeserializeRosString(m.data, m.location));
                            EXPECT_EQ(SerializeRosString(notes.back()), bytes);
                          }
                        });
    ASSERT_EQ(imu.size(), 5u);
    for (int i = 0; i < 5; ++i) {
      EXPECT_EQ(imu[i].header.seq, static_cast<uint32_t>(i));
      EXPECT_EQ(imu[i].header.stamp_ns, 100'000'000'000 + 5'000'000 * i + 1);
      EXPECT_EQ(imu[i].header.frame_id, "imu0");
      EXPECT_EQ(imu[i].angular_velocity, Eigen::Vector3d(0.1 * i, -0.25, 1.0 / 3.0));
      EXPECT_EQ(imu[i].linear_acceleration, Eigen::Vector3d(0.5, -0.125 * i, 9.81));
      EXPECT_EQ(imu[i].orientation_covariance(0, 0), -1.0);
    }
    ASSERT_EQ(images.size(), 3u);
    for (int j = 0; j < 3; ++j) {
      const int i = 2 * j;
      EXPECT_EQ(images[j].header.stamp_ns, 100'000'000'000 + 5'000'000 * i + 1);
      EXPECT_EQ(images[j].width, 4u);
      EXPECT_EQ(images[j].height, 3u);
      EXPECT_EQ(images[j].step, 4u);
      EXPECT_EQ(images[j].encoding, "mono8");
      ASSERT_EQ(images[j].data.size(), 12u);
      for (int k = 0; k < 12; ++k) EXPECT_EQ(images[j].data[k], 20 * i + k);
    }
    ASSERT_EQ(poses.size(), 1u);
    EXPECT_EQ(poses[0].header.stamp_ns, 100'000'000'007);
    EXPECT_EQ(poses[0].header.frame_id, "world");
    EXPECT_EQ(poses[0].pose.translation, Eigen::Vector3d(1.5, -2.0, 0.25));
    EXPECT_EQ(poses[0].pose.rotation.coeffs(), Eigen::Vector4d(0.5, 0.5, 0.5, 0.5));
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_EQ(notes[0], "hello bag");
  }
}

// Random messages on three connections, small chunks: every compression
// gives back the same messages in the same order, with counts.
TEST(Rosbag, WriterRoundTripsInEveryCompression) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_roundtrip");
  Random random(7);
  std::vector<ReadMessage> written;
  for (int i = 0; i < 300; ++i) {
    ReadMessage m;
    m.topic = i % 3 == 0 ? "/a" : (i % 3 == 1 ? "/b/c" : "/d");
    m.time_ns = 1'400'000'000'000'000'000 + 1'000'003 * i;
    m.data.resize(static_cast<size_t>(random.UniformInt(0, 3000)));
    for (uint8_t& byte : m.data) byte = static_cast<uint8_t>(random.UniformInt(0, 3));
    written.push_back(std::move(m));
  }
  for (const RosbagCompression compression :
       {RosbagCompression::kNone, RosbagCompression::kBz2, RosbagCompression::kLz4}) {
    SCOPED_TRACE(RosbagCompressionName(compression));
    const fs::path path = folder / (RosbagCompressionName(compression) + ".bag");
    {
      RosbagWriterOptions options;
      options.compression = compression;
      options.chunk_threshold_bytes = 20000;
      RosbagWriter writer(path, options);
      std::map<std::string, uint32_t> ids;
      for (const std::string topic : {"/a", "/b/c", "/d"}) {
        ids[topic] = writer.AddConnection(topic, "std_msgs/String", "*", "string data\n");
      }
      for (const ReadMessage& m : written) writer.Write(ids[m.topic], m.time_ns, m.data);
      writer.Close();
    }
    if (compression == RosbagCompression::kLz4) {
      // roslz4, ROS's reader, takes only LZ4 frames whose FLG byte is 0x64
      // (version 1, independent blocks, content checksum) with a block size
      // id of 4 to 7 in the BD byte.
      const std::string bytes = ReadFileBytes(path);
      const size_t magic = bytes.find(std::string("\x04\x22\x4d\x18", 4));
      ASSERT_NE(magic, std::string::npos);
      EXPECT_EQ(static_cast<uint8_t>(bytes[magic + 4]), 0x64);
      const int block_size_id = (static_cast<uint8_t>(bytes[magic + 5]) >> 4) & 7;
      EXPECT_GE(block_size_id, 4);
    }
    RosbagReader reader(path);
    EXPECT_TRUE(reader.has_index());
    ASSERT_EQ(reader.connections().size(), 3u);
    EXPECT_EQ(reader.connections()[1].topic, "/b/c");
    EXPECT_EQ(reader.connections()[1].type, "std_msgs/String");
    EXPECT_EQ(reader.connections()[1].message_definition, "string data\n");
    for (const RosbagConnection& c : reader.connections()) EXPECT_EQ(c.num_messages, 100u);
    const std::vector<ReadMessage> read = ReadAll(path);
    ASSERT_EQ(read.size(), written.size());
    for (size_t i = 0; i < read.size(); ++i) {
      ASSERT_EQ(read[i].topic, written[i].topic) << i;
      ASSERT_EQ(read[i].time_ns, written[i].time_ns) << i;
      ASSERT_EQ(read[i].data, written[i].data) << i;
    }
  }
}

// A bag whose recording stopped before the index was written (index_pos 0)
// is read by scanning, with the same messages and counts.
TEST(Rosbag, ReadsABagWithoutIndex) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_noindex");
  const fs::path source = testing::SourcePath("io/testdata/librosbag_lz4.bag");
  std::string bytes = ReadFileBytes(source);
  const size_t field = bytes.find("index_pos=");
  ASSERT_NE(field, std::string::npos);
  std::memset(bytes.data() + field + 10, 0, 8);
  const fs::path path = folder / "noindex.bag";
  WriteFileBytes(path, bytes);
  RosbagReader reader(path);
  EXPECT_FALSE(reader.has_index());
  uint64_t total = 0;
  for (const RosbagConnection& c : reader.connections()) total += c.num_messages;
  EXPECT_EQ(total, 10u);
  const std::vector<ReadMessage> with_index = ReadAll(source);
  const std::vector<ReadMessage> without = ReadAll(path);
  ASSERT_EQ(without.size(), with_index.size());
  for (size_t i = 0; i < without.size(); ++i) EXPECT_EQ(without[i].data, with_index[i].data);
}

TEST(Rosbag, TruncatedBagsNameTheOffset) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_truncated");
  const std::string bytes = ReadFileBytes(testing::SourcePath("io/testdata/librosbag_none.bag"));
  // Cut inside the index at the end: the header points past the end.
  const fs::path cut_index = folder / "cut_index.bag";
  WriteFileBytes(cut_index, bytes.substr(0, bytes.size() - 30));
  const std::string index_message =
      testing::InputErrorMessage([&] { RosbagReader reader(cut_index); });
  EXPECT_NE(index_message.find("cut_index.bag"), std::string::npos) << index_message;
  EXPECT_NE(index_message.find("truncated"), std::string::npos) << index_message;
  EXPECT_NE(index_message.find("byte offset"), std::string::npos) << index_message;

  // An interrupted recording (no index) cut inside a chunk.
  std::string no_index = bytes.substr(0, 6000);
  const size_t field = no_index.find("index_pos=");
  std::memset(no_index.data() + field + 10, 0, 8);
  const fs::path cut_chunk = folder / "cut_chunk.bag";
  WriteFileBytes(cut_chunk, no_index);
  const std::string chunk_message = testing::InputErrorMessage([&] {
    RosbagReader reader(cut_chunk);
    reader.ReadMessages([](const RosbagConnection&) { return true; }, [](const RosbagMessage&) {});
  });
  EXPECT_NE(chunk_message.find("cut_chunk.bag: byte offset "), std::string::npos) << chunk_message;
  EXPECT_NE(chunk_message.find("the file ends after"), std::string::npos) << chunk_message;

  // Only the version line.
  const fs::path cut_header = folder / "cut_header.bag";
  WriteFileBytes(cut_header, bytes.substr(0, 20));
  const std::string header_message =
      testing::InputErrorMessage([&] { RosbagReader reader(cut_header); });
  EXPECT_NE(header_message.find("byte offset 13"), std::string::npos) << header_message;
  EXPECT_NE(header_message.find("truncated"), std::string::npos) << header_message;
}

TEST(Rosbag, RejectsFilesThatAreNotRos1Bags) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_notbag");
  const auto message = [&](const std::string& name, const std::string& content) {
    WriteFileBytes(folder / name, content);
    return testing::InputErrorMessage([&] { RosbagReader reader(folder / name); });
  };
  EXPECT_NE(message("text.bag", "hello, this is not a bag at all\n").find("not a ROS 1 bag"),
            std::string::npos);
  EXPECT_NE(message("ros2.bag", std::string("SQLite format 3\0", 16) + std::string(100, 'x'))
                .find("ROS 2"),
            std::string::npos);
  EXPECT_NE(message("old.bag", "#ROSBAG V1.2\n" + std::string(100, 'x')).find("V1.2"),
            std::string::npos);
  EXPECT_NE(testing::InputErrorMessage([&] {
              RosbagReader reader(folder / "missing.bag");
            }).find("not found"),
            std::string::npos);
}

TEST(Rosbag, CorruptCompressedChunkIsAnError) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_corrupt");
  std::string bytes = ReadFileBytes(testing::SourcePath("io/testdata/librosbag_lz4.bag"));
  // Overwrite the compressed data of the first chunk (after its header).
  const size_t chunk = bytes.find("compression=lz4");
  ASSERT_NE(chunk, std::string::npos);
  for (size_t i = chunk + 40; i < chunk + 80; ++i) bytes[i] = static_cast<char>(0xAB);
  const fs::path path = folder / "corrupt.bag";
  WriteFileBytes(path, bytes);
  const std::string message = testing::InputErrorMessage([&] {
    RosbagReader reader(path);
    reader.ReadMessages([](const RosbagConnection&) { return true; }, [](const RosbagMessage&) {});
  });
  EXPECT_NE(message.find("corrupt.bag: byte offset "), std::string::npos) << message;
  EXPECT_NE(message.find("lz4"), std::string::npos) << message;
}

// Writes one highly compressible 6 MiB message in a single chunk: the
// decompressed chunk is hundreds of times its compressed data, far beyond the
// reader's first output buffer, which has to grow to the stated size.
fs::path WriteCompressibleBag(const fs::path& path, RosbagCompression compression,
                              std::vector<uint8_t>& message) {
  message.assign(6 << 20, 0);
  for (size_t i = 0; i < message.size(); i += 4096) message[i] = static_cast<uint8_t>(i >> 12);
  RosbagWriterOptions options;
  options.compression = compression;
  options.chunk_threshold_bytes = 16 << 20;
  RosbagWriter writer(path, options);
  const uint32_t id = writer.AddConnection("/a", "std_msgs/String", "*", "string data\n");
  writer.Write(id, 1'000'000'000, message);
  writer.Close();
  return path;
}

TEST(Rosbag, HighlyCompressedChunksDecompressWhole) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_ratio");
  for (const RosbagCompression compression : {RosbagCompression::kBz2, RosbagCompression::kLz4}) {
    SCOPED_TRACE(RosbagCompressionName(compression));
    std::vector<uint8_t> message;
    const fs::path path = WriteCompressibleBag(
        folder / (RosbagCompressionName(compression) + ".bag"), compression, message);
    EXPECT_LT(fs::file_size(path) * 16, message.size());  // beyond the first buffer
    const std::vector<ReadMessage> read = ReadAll(path);
    ASSERT_EQ(read.size(), 1u);
    EXPECT_TRUE(read[0].data == message);
  }
}

// The process's peak resident memory so far.
long PeakResidentKib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

// A chunk header may state up to 1 GiB of uncompressed data. The reader must
// notice that the data does not back the claim, naming the chunk, and not
// allocate the claimed size up front (make fuzz's malloc limit checks that).
TEST(Rosbag, ChunkStatingMoreThanItsDataGivesIsAnError) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_claim");
  for (const RosbagCompression compression : {RosbagCompression::kBz2, RosbagCompression::kLz4}) {
    const std::string name = RosbagCompressionName(compression);
    SCOPED_TRACE(name);
    std::vector<uint8_t> message;
    std::string bytes =
        ReadFileBytes(WriteCompressibleBag(folder / (name + ".bag"), compression, message));
    const size_t chunk = bytes.find("compression=" + name);
    ASSERT_NE(chunk, std::string::npos);
    const size_t size_field = bytes.find("size=", chunk);
    ASSERT_NE(size_field, std::string::npos);
    const uint32_t claimed = 900u << 20;
    std::memcpy(&bytes[size_field + 5], &claimed, 4);
    const fs::path path = folder / (name + "_claim.bag");
    WriteFileBytes(path, bytes);
    const long peak_before_kib = PeakResidentKib();
    const std::string error = testing::InputErrorMessage([&] { ReadAll(path); });
    // Zero-filling the claimed 900 MiB up front would raise the peak by as much.
    EXPECT_LT(PeakResidentKib() - peak_before_kib, 100 * 1024);
    EXPECT_NE(error.find(name + "_claim.bag: byte offset "), std::string::npos) << error;
    EXPECT_NE(error.find(std::to_string(claimed)), std::string::npos) << error;
    EXPECT_NE(error.find("header states"), std::string::npos) << error;
  }
}

TEST(Rosbag, WriterRejectsTimesOutsideRosTime) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_time");
  RosbagWriter writer(folder / "t.bag");
  const uint32_t id = writer.AddConnection("/a", "std_msgs/String", "*", "string data\n");
  EXPECT_NE(testing::InputErrorMessage([&] { writer.Write(id, -1, {}); }).find("ROS time"),
            std::string::npos);
}

TEST(Rosbag, UnclosedWriterLeavesNoFile) {
  const fs::path folder = testing::MakeScratchFolder("rosbag_unclosed");
  {
    RosbagWriter writer(folder / "u.bag");
    writer.AddConnection("/a", "std_msgs/String", "*", "string data\n");
  }
  EXPECT_TRUE(fs::is_empty(folder));
}

}  // namespace
}  // namespace viosfm

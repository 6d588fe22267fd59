// MCAP files (mcap.dev/spec, major version 0): the container only. ROS 2
// records them (rosbag2's default storage since Iron); what a message's
// bytes mean is ros_messages.h's business (CDR for the "ros2" profile).
//
// Layout: the magic 89 'M' 'C' 'A' 'P' '0' '\r' '\n', the records, the magic
// again. A record is uint8 opcode, uint64 content length, content; all
// integers little-endian, a string is uint32 length + bytes, a map or an
// array is uint32 byte length + its entries. The records:
//   0x01 Header       profile, library (first)
//   0x02 Footer       summary_start, summary_offset_start (uint64), summary_crc (last)
//   0x03 Schema       id (uint16), name, encoding, data (uint32-prefixed bytes)
//   0x04 Channel      id, schema_id (uint16), topic, message_encoding, metadata
//   0x05 Message      channel_id (uint16), sequence (uint32), log_time,
//                     publish_time (uint64 ns), data (the rest)
//   0x06 Chunk        message_start_time, message_end_time, uncompressed_size
//                     (uint64), uncompressed_crc (uint32), compression ("",
//                     "zstd", "lz4": an LZ4 frame), records (uint64-prefixed):
//                     Schema, Channel and Message records
//   0x07 Message Index, 0x08 Chunk Index, 0x09 Attachment, 0x0A Attachment
//   Index, 0x0B Statistics, 0x0C Metadata, 0x0D Metadata Index, 0x0E Summary
//   Offset, 0x0F Data End (data_section_crc)
// The data section ends with Data End; the optional summary section after it
// repeats the schemas and channels and holds the indexes and statistics.
// CRCs are CRC-32 (the zlib one); a CRC of 0 means "not computed".
//
// Reading takes the channels (and their message counts) from the summary
// when there is one, else from a scan of the file; messages are always read
// by scanning the data section in file order, every chunk decompressed and
// its CRC checked, so the indexes need not be trusted. Every malformed or
// truncated record, CRC mismatch or unknown compression throws InputError
// naming the file, the byte offset (inside a chunk: the chunk's and the
// offset in its records) and what was expected.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "viosfm/util/timestamp.h"

namespace viosfm {

// The 8 bytes an MCAP file begins and ends with.
inline constexpr uint8_t kMcapMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// CRC-32 (polynomial 0xEDB88320, as zlib and MCAP), continued from `crc`.
uint32_t Crc32(std::span<const uint8_t> data, uint32_t crc = 0);

struct McapChannel {
  uint16_t id = 0;
  std::string topic;
  std::string message_encoding;  // "cdr" for ROS 2
  std::map<std::string, std::string> metadata;
  uint16_t schema_id = 0;       // 0: no schema
  std::string schema_name;      // "sensor_msgs/msg/Image"
  std::string schema_encoding;  // "ros2msg"
  std::string schema_data;      // the message definition
  uint64_t num_messages = 0;    // from the statistics, or counted
};

struct McapMessage {
  const McapChannel* channel = nullptr;
  uint32_t sequence = 0;
  timestamp_ns_t log_time_ns = 0;
  timestamp_ns_t publish_time_ns = 0;
  std::span<const uint8_t> data;  // valid during the callback
  // "byte offset 5012" or "chunk at byte offset 4117 (zstd), offset 920 of its records".
  std::string location;
};

class McapReader {
 public:
  // Opens the file and reads its channels. Throws InputError if it cannot
  // be opened, is not MCAP, is truncated or a record is malformed.
  explicit McapReader(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  const std::string& profile() const { return profile_; }
  const std::string& library() const { return library_; }
  // Ordered by channel id.
  const std::vector<McapChannel>& channels() const { return channels_; }
  bool has_summary() const { return summary_start_ != 0; }

  // Calls `visit` for every message whose channel `wanted` accepts, in file
  // order. Throws InputError on a malformed record or a CRC mismatch.
  void ReadMessages(const std::function<bool(const McapChannel&)>& wanted,
                    const std::function<void(const McapMessage&)>& visit);

 private:
  struct Scan;
  class Records;
  void ReadFooter();
  void ReadSummary();
  class RecordScanner;
  void ScanData(Scan& scan);
  void AddSchema(uint16_t id, std::string name, std::string encoding, std::string data,
                 const std::string& location);
  void AddChannel(McapChannel channel, const std::string& location);

  std::filesystem::path path_;
  std::ifstream file_;
  uint64_t file_size_ = 0;
  std::string profile_;
  std::string library_;
  uint64_t footer_offset_ = 0;
  uint64_t summary_start_ = 0;
  uint64_t summary_offset_start_ = 0;
  uint32_t summary_crc_ = 0;
  struct Schema {
    std::string name;
    std::string encoding;
    std::string data;
  };
  std::map<uint16_t, Schema> schemas_;
  std::vector<McapChannel> channels_;
  std::map<uint16_t, size_t> channel_index_;  // id -> position in channels_
};

enum class McapCompression { kNone, kZstd, kLz4 };
// "", "zstd", "lz4" as the file states it; "none" for kNone in messages.
std::string McapCompressionName(McapCompression compression);

struct McapWriterOptions {
  // A chunk is written when its uncompressed records exceed this (bytes).
  // Default 4 MiB.
  size_t chunk_threshold_bytes = 4 * 1024 * 1024;
  // Chunk compression. Default zstd (ROS 2's rosbag2 default).
  McapCompression compression = McapCompression::kZstd;
  // Write the summary section (schemas, channels, statistics, chunk
  // indexes, summary offsets) and the message indexes. Default true.
  bool summary = true;
  // The Header record's profile. Default "ros2".
  std::string profile = "ros2";
};

// Writes an MCAP file atomically: to "<path>.tmp-<pid>", renamed to `path`
// by Close(). A writer destroyed without Close() removes its temporary file.
class McapWriter {
 public:
  explicit McapWriter(const std::filesystem::path& path, const McapWriterOptions& options = {});
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Returns the new schema's id (from 1).
  uint16_t AddSchema(const std::string& name, const std::string& encoding, const std::string& data);
  // Returns the new channel's id (from 1).
  uint16_t AddChannel(const std::string& topic, uint16_t schema_id,
                      const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata);
  // log_time_ns and publish_time_ns must be >= 0.
  void Write(uint16_t channel_id, timestamp_ns_t log_time_ns, timestamp_ns_t publish_time_ns,
             std::span<const uint8_t> data);
  void Close();

 private:
  void FlushChunk();
  void WriteBytes(const std::string& bytes);

  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  McapWriterOptions options_;
  std::ofstream file_;
  uint64_t position_ = 0;
  uint32_t data_crc_ = 0;
  bool in_data_section_ = true;
  bool closed_ = false;
  struct Record {
    std::string bytes;  // the complete record
    bool written = false;
  };
  std::vector<Record> schemas_;   // id - 1
  std::vector<Record> channels_;  // id - 1
  std::vector<uint16_t> channel_schema_;
  std::vector<uint32_t> channel_sequence_;
  std::vector<uint64_t> channel_count_;
  // The chunk being filled.
  std::string chunk_records_;
  timestamp_ns_t chunk_start_ns_ = 0;
  timestamp_ns_t chunk_end_ns_ = 0;
  uint64_t chunk_messages_ = 0;
  std::map<uint16_t, std::vector<std::pair<timestamp_ns_t, uint64_t>>> chunk_index_;
  std::vector<std::string> chunk_index_records_;
  uint64_t message_count_ = 0;
  uint32_t chunk_count_ = 0;
  timestamp_ns_t start_ns_ = 0;
  timestamp_ns_t end_ns_ = 0;
};

}  // namespace viosfm

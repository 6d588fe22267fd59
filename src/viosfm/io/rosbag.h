// ROS 1 bag files, format version 2.0 (wiki.ros.org/Bags/Format/2.0): the
// container only (records, chunks, connections, index). What a message's
// bytes mean is ros_messages.h's business.
//
// Layout: the line "#ROSBAG V2.0\n", then records. A record is
//   uint32 header_len, header (fields: uint32 field_len, "name=value"),
//   uint32 data_len, data
// all little-endian. The field "op" (one byte) gives the record's kind:
//   0x03 bag header   index_pos (uint64), conn_count, chunk_count (uint32);
//                     the record is padded to 4096 bytes so it can be rewritten
//   0x05 chunk        compression ("none", "bz2", "lz4"), size (uint32,
//                     uncompressed); data: connection and message records
//   0x07 connection   conn (uint32), topic; data: a header with topic, type,
//                     md5sum, message_definition (and optional callerid, latching)
//   0x02 message data conn (uint32), time (uint32 sec, uint32 nsec); data: the
//                     serialized message
//   0x04 index data   ver 1, conn, count; data: count x (time, uint32 offset
//                     of the message record in the chunk's uncompressed data)
//   0x06 chunk info   ver 1, chunk_pos (uint64), start_time, end_time, count;
//                     data: count x (uint32 conn, uint32 message count)
// Chunks come first, each followed by its index data records; the bag
// header's index_pos points at the connection and chunk-info records at the
// end of the file.
//
// Why viosfm reads and writes the format itself rather than through Debian's
// librosbag-storage-dev: see docs/design.md ("ROS bags").
//
// Reading scans the records in file order (it does not need the index, so a
// bag whose recording was interrupted before the index was written can be
// read). Every malformed or truncated record throws InputError naming the
// file, the byte offset (and, inside a compressed chunk, the offset in the
// chunk's uncompressed data) and what was expected.
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

// The first line of every ROS 1 bag of format 2.0.
inline constexpr char kRosbagVersionLine[] = "#ROSBAG V2.0\n";

// Whether a path names a ROS 1 bag by its extension (".bag", any case).
bool HasRosbagExtension(const std::filesystem::path& path);

struct RosbagConnection {
  uint32_t id = 0;
  std::string topic;
  std::string type;    // "sensor_msgs/Image"
  std::string md5sum;  // the message type's MD5 sum ("*" for any)
  std::string message_definition;
  // Number of messages on this connection (from the chunk-info records, or
  // counted while scanning a bag without an index).
  uint64_t num_messages = 0;
};

struct RosbagMessage {
  const RosbagConnection* connection = nullptr;
  timestamp_ns_t time_ns = 0;     // the record time (when the message was recorded)
  std::span<const uint8_t> data;  // the serialized message, valid during the callback
  // Where the message record is, for error messages: "byte offset 5012" or
  // "chunk at byte offset 4117 (lz4), offset 920 of its data".
  std::string location;
};

class RosbagReader {
 public:
  // Opens the bag and reads its connections (from the index at the end, or
  // by scanning the file when the bag has no index). Throws InputError if
  // the file cannot be opened, is not a ROS 1 bag of format 2.0, or a record
  // is malformed.
  explicit RosbagReader(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  // Ordered by connection id.
  const std::vector<RosbagConnection>& connections() const { return connections_; }
  // Whether the bag header pointed at an index (false: interrupted recording).
  bool has_index() const { return has_index_; }

  // Calls `visit` for every message whose connection `wanted` accepts, in
  // file order (for a bag written in time order, which rosbag record and
  // viosfm do, that is time order per topic). Throws InputError on a
  // malformed or truncated record.
  void ReadMessages(const std::function<bool(const RosbagConnection&)>& wanted,
                    const std::function<void(const RosbagMessage&)>& visit);

 private:
  struct Scan;
  class RecordScanner;
  void ScanRecords(Scan& scan);
  void AddConnection(RosbagConnection connection, const std::string& location);

  std::filesystem::path path_;
  std::ifstream file_;
  uint64_t file_size_ = 0;
  uint64_t first_record_offset_ = 0;  // after the bag header record
  uint64_t index_pos_ = 0;
  bool has_index_ = false;
  std::vector<RosbagConnection> connections_;
  std::map<uint32_t, size_t> connection_index_;  // id -> position in connections_
};

enum class RosbagCompression { kNone, kBz2, kLz4 };
// "none", "bz2", "lz4".
std::string RosbagCompressionName(RosbagCompression compression);

struct RosbagWriterOptions {
  // A chunk is written when its uncompressed data exceeds this (bytes).
  // Default 768 KiB, rosbag record's.
  size_t chunk_threshold_bytes = 768 * 1024;
  // Chunk compression. Default none (EuRoC's bags are uncompressed).
  RosbagCompression compression = RosbagCompression::kNone;
};

// Writes a bag atomically: to "<path>.tmp-<pid>", renamed to `path` by
// Close(). A writer destroyed without Close() removes its temporary file.
// Messages must be written with non-decreasing time per connection.
class RosbagWriter {
 public:
  explicit RosbagWriter(const std::filesystem::path& path, const RosbagWriterOptions& options = {});
  ~RosbagWriter();
  RosbagWriter(const RosbagWriter&) = delete;
  RosbagWriter& operator=(const RosbagWriter&) = delete;

  // Returns the new connection's id.
  uint32_t AddConnection(const std::string& topic, const std::string& type,
                         const std::string& md5sum, const std::string& message_definition);
  // time_ns must lie in [0, 2^32 s) (ROS time is uint32 seconds).
  void Write(uint32_t connection_id, timestamp_ns_t time_ns, std::span<const uint8_t> data);
  void Close();

 private:
  struct ChunkInfo {
    uint64_t position = 0;
    timestamp_ns_t start_ns = 0;
    timestamp_ns_t end_ns = 0;
    std::map<uint32_t, uint32_t> counts;
  };
  void FlushChunk();
  void WriteBytes(const std::string& bytes);

  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  RosbagWriterOptions options_;
  std::ofstream file_;
  uint64_t position_ = 0;
  bool closed_ = false;
  // Connections: header record text (without the op=7 record framing).
  struct Connection {
    std::string topic;
    std::string record;  // the complete connection record
    bool written_in_chunk = false;
  };
  std::vector<Connection> connections_;
  // The chunk being filled.
  std::string chunk_data_;
  ChunkInfo chunk_;
  std::map<uint32_t, std::vector<std::pair<timestamp_ns_t, uint32_t>>> chunk_index_;
  std::vector<ChunkInfo> chunks_;
};

}  // namespace viosfm

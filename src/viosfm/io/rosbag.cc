#include "viosfm/io/rosbag.h"

#include <bzlib.h>
#include <lz4frame.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <string_view>
#include <system_error>

#include "viosfm/io/bag_bytes.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

constexpr uint8_t kOpMessageData = 0x02;
constexpr uint8_t kOpBagHeader = 0x03;
constexpr uint8_t kOpIndexData = 0x04;
constexpr uint8_t kOpChunkRecord = 0x05;
constexpr uint8_t kOpChunkInfo = 0x06;
constexpr uint8_t kOpConnection = 0x07;
constexpr size_t kBagHeaderRecordBytes = 4096;
// Largest uncompressed chunk accepted (rosbag record writes 768 KiB chunks).
constexpr uint32_t kMaxUncompressedChunkBytes = uint32_t{1} << 30;

std::string U32Bytes(uint32_t value) {
  std::string out;
  AppendU32(out, value);
  return out;
}
std::string U64Bytes(uint64_t value) {
  std::string out;
  AppendU64(out, value);
  return out;
}
// ROS time: uint32 seconds, uint32 nanoseconds.
std::string TimeBytes(timestamp_ns_t time_ns) {
  std::string out;
  AppendU32(out, static_cast<uint32_t>(time_ns / 1'000'000'000));
  AppendU32(out, static_cast<uint32_t>(time_ns % 1'000'000'000));
  return out;
}

// The fields of a record header, "name" -> raw value bytes.
using HeaderFields = std::map<std::string, std::string, std::less<>>;

// Parses header fields; returns an error text, empty on success.
std::string ParseHeaderFields(std::span<const uint8_t> bytes, HeaderFields* fields) {
  size_t offset = 0;
  while (offset < bytes.size()) {
    if (bytes.size() - offset < 4) {
      return "a header field length needs 4 bytes, " + std::to_string(bytes.size() - offset) +
             " left in the header";
    }
    const uint32_t length = LoadU32(bytes.data() + offset);
    offset += 4;
    if (length > bytes.size() - offset) {
      return "a header field of " + std::to_string(length) + " bytes overruns the header (" +
             std::to_string(bytes.size() - offset) + " left)";
    }
    const std::string_view field(reinterpret_cast<const char*>(bytes.data() + offset), length);
    offset += length;
    const size_t equals = field.find('=');
    if (equals == std::string_view::npos) {
      return "header field without '=' ('" + std::string(field.substr(0, 40)) + "')";
    }
    (*fields)[std::string(field.substr(0, equals))] = std::string(field.substr(equals + 1));
  }
  return "";
}

std::string EncodeHeader(const std::vector<std::pair<std::string, std::string>>& fields) {
  std::string header;
  for (const auto& [name, value] : fields) {
    AppendU32(header, static_cast<uint32_t>(name.size() + 1 + value.size()));
    header += name;
    header += '=';
    header += value;
  }
  return header;
}

std::string EncodeRecord(const std::vector<std::pair<std::string, std::string>>& fields,
                         std::string_view data) {
  const std::string header = EncodeHeader(fields);
  std::string record;
  record.reserve(8 + header.size() + data.size());
  AppendU32(record, static_cast<uint32_t>(header.size()));
  record += header;
  AppendU32(record, static_cast<uint32_t>(data.size()));
  record += data;
  return record;
}

// A record's header fields with typed access; failures name the location.
class RecordHeader {
 public:
  RecordHeader(HeaderFields fields, std::string path, std::string location)
      : fields_(std::move(fields)), path_(std::move(path)), location_(std::move(location)) {}

  bool Has(std::string_view name) const { return fields_.find(name) != fields_.end(); }
  const std::string& Bytes(std::string_view name, size_t expected_size = 0) const {
    const auto it = fields_.find(name);
    if (it == fields_.end()) Fail("the record header has no field '" + std::string(name) + "'");
    if (expected_size > 0 && it->second.size() != expected_size) {
      Fail("header field '" + std::string(name) + "' has " + std::to_string(it->second.size()) +
           " bytes, expected " + std::to_string(expected_size));
    }
    return it->second;
  }
  uint8_t Op() const { return static_cast<uint8_t>(Bytes("op", 1)[0]); }
  uint32_t U32(std::string_view name) const {
    return LoadU32(reinterpret_cast<const uint8_t*>(Bytes(name, 4).data()));
  }
  uint64_t U64(std::string_view name) const {
    return LoadU64(reinterpret_cast<const uint8_t*>(Bytes(name, 8).data()));
  }
  timestamp_ns_t Time(std::string_view name) const {
    const std::string& bytes = Bytes(name, 8);
    const uint32_t sec = LoadU32(reinterpret_cast<const uint8_t*>(bytes.data()));
    const uint32_t nsec = LoadU32(reinterpret_cast<const uint8_t*>(bytes.data()) + 4);
    if (nsec >= 1'000'000'000u) {
      Fail("header field '" + std::string(name) + "' has " + std::to_string(nsec) +
           " nanoseconds (expected < 1e9)");
    }
    return static_cast<timestamp_ns_t>(sec) * 1'000'000'000 + nsec;
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_, 0, location_ + ": " + what);
  }

 private:
  HeaderFields fields_;
  std::string path_;
  std::string location_;
};

}  // namespace

bool HasRosbagExtension(const fs::path& path) {
  return ToLower(path.extension().string()) == ".bag";
}

std::string RosbagCompressionName(RosbagCompression compression) {
  switch (compression) {
    case RosbagCompression::kNone: return "none";
    case RosbagCompression::kBz2: return "bz2";
    case RosbagCompression::kLz4: return "lz4";
  }
  return "none";
}

// ----------------------------------------------------------------------------
// Reader

struct RosbagReader::Scan {
  // Whether to decode message records (false: collect connections only).
  bool messages = false;
  // Count messages per connection (for a bag without index).
  bool count = false;
  std::function<bool(const RosbagConnection&)> wanted;
  std::function<void(const RosbagMessage&)> visit;
};

namespace {

// The output buffer of a decompression grows with what the data actually
// gives, up to the size the chunk's header states: a corrupt or hostile header
// claiming up to 1 GiB then costs memory only in proportion to the data that
// backs it. The first allocation allows a compression ratio of 16.
size_t InitialOutputSize(size_t compressed_size, uint32_t stated_size) {
  constexpr size_t kMinInitial = size_t{1} << 20;
  return std::min<size_t>(stated_size, std::max(kMinInitial, 16 * compressed_size));
}

// Doubles `out` (at most to `stated_size`); false when it is already there.
bool GrowOutput(std::vector<uint8_t>& out, uint32_t stated_size) {
  if (out.size() >= stated_size) return false;
  out.resize(std::min<size_t>(stated_size, 2 * out.size()));
  return true;
}

std::vector<uint8_t> DecompressBz2(const RecordHeader& header, std::span<const uint8_t> data,
                                   uint32_t size) {
  std::vector<uint8_t> out(InitialOutputSize(data.size(), size));
  bz_stream stream{};
  if (BZ2_bzDecompressInit(&stream, 0, 0) != BZ_OK) {
    header.Fail("cannot create a bzip2 decompression context");
  }
  stream.next_in = const_cast<char*>(reinterpret_cast<const char*>(data.data()));
  stream.avail_in = static_cast<unsigned int>(data.size());
  size_t produced = 0;
  int status = BZ_OK;
  bool overflow = false;
  while (true) {
    stream.next_out = reinterpret_cast<char*>(out.data() + produced);
    stream.avail_out = static_cast<unsigned int>(out.size() - produced);
    status = BZ2_bzDecompress(&stream);
    produced = out.size() - stream.avail_out;
    if (status != BZ_OK) break;  // BZ_STREAM_END or an error
    if (stream.avail_out == 0) {
      if (!GrowOutput(out, size)) {
        overflow = true;
        break;
      }
    } else if (stream.avail_in == 0) {
      break;  // the data ends before the stream does
    }
  }
  BZ2_bzDecompressEnd(&stream);
  if (status != BZ_STREAM_END || overflow || produced != size) {
    header.Fail("bz2 chunk does not decompress to the " + std::to_string(size) +
                " bytes its header states (" +
                (overflow ? std::string("it gives more")
                          : "bzip2 status " + std::to_string(status) + ", " +
                                std::to_string(produced) + " bytes") +
                ")");
  }
  return out;
}

std::vector<uint8_t> DecompressLz4(const RecordHeader& header, std::span<const uint8_t> data,
                                   uint32_t size) {
  std::vector<uint8_t> out(InitialOutputSize(data.size(), size));
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    header.Fail("cannot create an lz4 decompression context");
  }
  size_t in_offset = 0;
  size_t out_offset = 0;
  size_t status = 1;
  bool overflow = false;
  // With the input consumed, a call with no input flushes what the decoder
  // still holds; the loop ends at the frame's end or when nothing moves.
  while (status != 0) {
    if (out_offset == out.size() && !GrowOutput(out, size)) {
      overflow = true;
      break;
    }
    size_t in_size = data.size() - in_offset;
    size_t out_size = out.size() - out_offset;
    status = LZ4F_decompress(context, out.data() + out_offset, &out_size, data.data() + in_offset,
                             &in_size, nullptr);
    if (LZ4F_isError(status)) {
      const std::string name = LZ4F_getErrorName(status);
      LZ4F_freeDecompressionContext(context);
      header.Fail("lz4 chunk cannot be decompressed (" + name + ")");
    }
    in_offset += in_size;
    out_offset += out_size;
    if (in_size == 0 && out_size == 0) break;
  }
  LZ4F_freeDecompressionContext(context);
  if (overflow || out_offset != size) {
    header.Fail("lz4 chunk decompresses to " +
                (overflow ? "more than " + std::to_string(size) : std::to_string(out_offset)) +
                " bytes, its header states " + std::to_string(size));
  }
  return out;
}

std::vector<uint8_t> Decompress(const RecordHeader& header, const std::string& compression,
                                std::span<const uint8_t> data, uint32_t size) {
  if (compression == "bz2") return DecompressBz2(header, data, size);
  if (compression == "lz4") return DecompressLz4(header, data, size);
  header.Fail("unknown chunk compression '" + compression + "' (expected none, bz2 or lz4)");
}

}  // namespace

RosbagReader::RosbagReader(const fs::path& path) : path_(path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw InputError(path.string(), 0, "bag file not found");
  }
  file_size_ = fs::file_size(path, error);
  file_.open(path, std::ios::binary);
  if (error || !file_) throw InputError(path.string(), 0, "cannot open the bag file");
  const std::string p = path.string();

  // The version line.
  const size_t version_size = sizeof(kRosbagVersionLine) - 1;
  std::string version(version_size, '\0');
  if (file_size_ < version_size) {
    throw InputError(p, 0,
                     "not a ROS 1 bag: the file has " + std::to_string(file_size_) +
                         " bytes, expected the line '#ROSBAG V2.0'");
  }
  ReadAt(file_, p, file_size_, 0, reinterpret_cast<uint8_t*>(version.data()), version_size,
         "version line", "bag");
  if (version != kRosbagVersionLine) {
    if (version.starts_with("SQLite format")) {
      throw InputError(p, 0,
                       "a SQLite file, not a ROS 1 bag: a ROS 2 bag (rosbag2's sqlite3 "
                       "storage), which viosfm reads as a .db3 file or its bag folder");
    }
    if (version.starts_with("#ROSBAG V")) {
      throw InputError(p, 0,
                       "bag format '" + std::string(Trim(version)) +
                           "' is not supported (expected '#ROSBAG V2.0', written by ROS 1 since "
                           "C Turtle); run `rosbag fix` on it");
    }
    throw InputError(p, 0, "not a ROS 1 bag: expected the first line '#ROSBAG V2.0'");
  }

  // The bag header record.
  uint64_t offset = version_size;
  uint8_t length_bytes[4];
  ReadAt(file_, p, file_size_, offset, length_bytes, 4, "bag header record length", "bag");
  const uint32_t header_length = LoadU32(length_bytes);
  if (header_length > file_size_ - offset - 4) {
    throw InputError(p, 0,
                     ByteOffset(offset) + ": bag header record of " +
                         std::to_string(header_length) + " bytes, the file ends after " +
                         std::to_string(file_size_ - offset - 4) + " (the bag is truncated)");
  }
  std::vector<uint8_t> header_bytes(header_length);
  ReadAt(file_, p, file_size_, offset + 4, header_bytes.data(), header_length, "bag header record",
         "bag");
  HeaderFields fields;
  if (const std::string problem = ParseHeaderFields(header_bytes, &fields); !problem.empty()) {
    throw InputError(p, 0, ByteOffset(offset) + ": bag header record: " + problem);
  }
  const RecordHeader header(std::move(fields), p, ByteOffset(offset) + " (bag header record)");
  if (header.Op() != kOpBagHeader) {
    header.Fail("expected the bag header record (op 0x03) first, found op " +
                std::to_string(header.Op()));
  }
  index_pos_ = header.U64("index_pos");
  ReadAt(file_, p, file_size_, offset + 4 + header_length, length_bytes, 4,
         "bag header record data length", "bag");
  const uint32_t padding = LoadU32(length_bytes);
  first_record_offset_ = offset + 8 + uint64_t{header_length} + padding;
  if (first_record_offset_ > file_size_) {
    header.Fail("the bag header's padding runs past the end of the file (the bag is truncated)");
  }
  if (index_pos_ != 0 && index_pos_ > file_size_) {
    header.Fail("the index starts at byte offset " + std::to_string(index_pos_) +
                " but the file has " + std::to_string(file_size_) +
                " bytes (the bag is truncated)");
  }
  has_index_ = index_pos_ >= first_record_offset_;

  // Connections: from the index section when there is one, else by scanning.
  Scan scan;
  scan.messages = false;
  scan.count = !has_index_;
  ScanRecords(scan);
}

void RosbagReader::AddConnection(RosbagConnection connection, const std::string& location) {
  const auto existing = connection_index_.find(connection.id);
  if (existing != connection_index_.end()) {
    const RosbagConnection& known = connections_[existing->second];
    if (known.topic != connection.topic || known.type != connection.type) {
      throw InputError(path_.string(), 0,
                       location + ": connection " + std::to_string(connection.id) +
                           " is defined twice with different topics or types ('" + known.topic +
                           "' " + known.type + ", '" + connection.topic + "' " + connection.type +
                           ")");
    }
    return;
  }
  // Keep connections_ ordered by id.
  const auto position =
      std::lower_bound(connections_.begin(), connections_.end(), connection.id,
                       [](const RosbagConnection& c, uint32_t id) { return c.id < id; });
  connections_.insert(position, std::move(connection));
  connection_index_.clear();
  for (size_t i = 0; i < connections_.size(); ++i) connection_index_[connections_[i].id] = i;
}

namespace {

// One record parsed from a buffer (a chunk's data).
struct ParsedRecord {
  RecordHeader header;
  std::span<const uint8_t> data;
  size_t size;  // header, data and their lengths
};

}  // namespace

// The records of the bag file in order, each handed to the step its op
// names: connections, messages, chunk infos (message counts), and chunks,
// whose own records are handed on in turn.
class RosbagReader::RecordScanner {
 public:
  RecordScanner(RosbagReader& reader, Scan& scan)
      : reader_(reader), scan_(scan), p_(reader.path_.string()) {}

  void Run() {
    // With an index and no messages wanted, read only the index section.
    uint64_t offset =
        (reader_.has_index_ && !scan_.messages) ? reader_.index_pos_ : reader_.first_record_offset_;
    while (offset < reader_.file_size_) offset = ScanRecordAt(offset);
  }

 private:
  // Reads the record at `offset` of the file, takes it if the scan wants
  // it; returns the offset of the next one.
  uint64_t ScanRecordAt(uint64_t offset) {
    const std::string location = ByteOffset(offset);
    const uint64_t file_size = reader_.file_size_;
    uint8_t length_bytes[4];
    ReadAt(reader_.file_, p_, file_size, offset, length_bytes, 4, "record header length", "bag");
    const uint32_t header_length = LoadU32(length_bytes);
    if (header_length > file_size - offset - 4) {
      throw InputError(p_, 0,
                       location + ": record header of " + std::to_string(header_length) +
                           " bytes, the file ends after " + std::to_string(file_size - offset - 4) +
                           " (the bag is truncated or corrupt)");
    }
    header_bytes_.resize(header_length);
    ReadAt(reader_.file_, p_, file_size, offset + 4, header_bytes_.data(), header_length,
           "record header", "bag");
    HeaderFields fields;
    if (const std::string problem = ParseHeaderFields(header_bytes_, &fields); !problem.empty()) {
      throw InputError(p_, 0, location + ": record header: " + problem);
    }
    const RecordHeader header(std::move(fields), p_, location);
    const uint8_t op = header.Op();
    ReadAt(reader_.file_, p_, file_size, offset + 4 + header_length, length_bytes, 4,
           "record data length", "bag");
    const uint32_t data_length = LoadU32(length_bytes);
    const uint64_t data_offset = offset + 8 + header_length;
    const uint64_t next = data_offset + data_length;
    if (next > file_size) {
      throw InputError(p_, 0,
                       location + ": record (op " + std::to_string(op) + ") data: expected " +
                           std::to_string(data_length) + " bytes, the file ends after " +
                           std::to_string(file_size - data_offset) + " (the bag is truncated)");
    }
    if (WantsData(op)) {
      data_bytes_.resize(data_length);
      ReadAt(reader_.file_, p_, file_size, data_offset, data_bytes_.data(), data_length,
             "record data", "bag");
      TakeRecord(op, header, data_bytes_, data_offset, location);
    } else if (op != kOpChunkRecord && op != kOpIndexData && op != kOpMessageData) {
      header.Fail("unknown record op " + std::to_string(op) +
                  " (expected 0x02 to 0x07 after the bag header)");
    }
    return next;
  }

  // Whether the scan needs the data of a record of `op`.
  bool WantsData(uint8_t op) const {
    return op == kOpConnection || op == kOpChunkInfo ||
           ((scan_.messages || scan_.count) && op == kOpMessageData) ||
           (op == kOpChunkRecord && (scan_.messages || !reader_.has_index_));
  }

  void TakeRecord(uint8_t op, const RecordHeader& header, std::span<const uint8_t> data,
                  uint64_t data_offset, const std::string& location) {
    if (op == kOpConnection) {
      TakeConnection(header, data, location);
    } else if (op == kOpChunkInfo) {
      TakeChunkInfo(header, data);
    } else if (op == kOpMessageData) {
      TakeMessage(header, data, location);
    } else if (op == kOpChunkRecord) {
      TakeChunk(header, data, data_offset, location);
    }
  }

  void TakeConnection(const RecordHeader& header, std::span<const uint8_t> data,
                      const std::string& location) {
    RosbagConnection connection;
    connection.id = header.U32("conn");
    connection.topic = header.Bytes("topic");
    HeaderFields fields;
    if (const std::string problem = ParseHeaderFields(data, &fields); !problem.empty()) {
      header.Fail("connection header: " + problem);
    }
    const RecordHeader connection_header(std::move(fields), p_, location + " (connection header)");
    connection.type = connection_header.Bytes("type");
    connection.md5sum = connection_header.Bytes("md5sum");
    if (connection_header.Has("message_definition")) {
      connection.message_definition = connection_header.Bytes("message_definition");
    }
    reader_.AddConnection(std::move(connection), location);
  }

  void TakeMessage(const RecordHeader& header, std::span<const uint8_t> data,
                   const std::string& location) {
    const uint32_t id = header.U32("conn");
    const timestamp_ns_t time_ns = header.Time("time");
    const auto it = reader_.connection_index_.find(id);
    if (it == reader_.connection_index_.end()) {
      header.Fail("message on connection " + std::to_string(id) +
                  ", which no connection record before it defines");
    }
    RosbagConnection& connection = reader_.connections_[it->second];
    if (scan_.count) ++connection.num_messages;
    if (!scan_.messages || !scan_.wanted(connection)) return;
    RosbagMessage message;
    message.connection = &connection;
    message.time_ns = time_ns;
    message.data = data;
    message.location = location;
    scan_.visit(message);
  }

  // Chunk info records of an indexed bag carry the message counts.
  void TakeChunkInfo(const RecordHeader& header, std::span<const uint8_t> data) {
    if (scan_.count || !reader_.has_index_ || scan_.messages) return;
    const uint32_t count = header.U32("count");
    if (data.size() != uint64_t{count} * 8) {
      header.Fail("chunk info data has " + std::to_string(data.size()) + " bytes, expected " +
                  std::to_string(uint64_t{count} * 8) + " for " + std::to_string(count) +
                  " connections");
    }
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t id = LoadU32(data.data() + 8 * i);
      const uint32_t messages = LoadU32(data.data() + 8 * i + 4);
      const auto it = reader_.connection_index_.find(id);
      if (it == reader_.connection_index_.end()) {
        header.Fail("chunk info counts messages of connection " + std::to_string(id) +
                    ", which no connection record defines");
      }
      reader_.connections_[it->second].num_messages += messages;
    }
  }

  // A chunk's records (connections and messages), decompressed first.
  void TakeChunk(const RecordHeader& header, std::span<const uint8_t> data, uint64_t data_offset,
                 const std::string& location) {
    const std::string compression = header.Bytes("compression");
    const uint32_t size = header.U32("size");
    std::vector<uint8_t> decompressed;
    std::span<const uint8_t> chunk = data;
    if (compression != "none") {
      if (size > kMaxUncompressedChunkBytes) {
        header.Fail("chunk states an uncompressed size of " + std::to_string(size) +
                    " bytes (more than 1 GiB: a corrupt header?)");
      }
      decompressed = Decompress(header, compression, data, size);
      chunk = decompressed;
    } else if (size != data.size()) {
      header.Fail("uncompressed chunk of " + std::to_string(data.size()) + " bytes states size " +
                  std::to_string(size));
    }
    size_t inner = 0;
    while (inner < chunk.size()) {
      const std::string inner_location =
          compression == "none" ? ByteOffset(data_offset + inner)
                                : "chunk at " + location + " (" + compression + "), offset " +
                                      std::to_string(inner) + " of its data";
      ParsedRecord record = ParseInBuffer(chunk, inner, inner_location);
      const uint8_t inner_op = record.header.Op();
      if (inner_op == kOpConnection) {
        TakeConnection(record.header, record.data, inner_location);
      } else if (inner_op == kOpMessageData) {
        TakeMessage(record.header, record.data, inner_location);
      } else {
        record.header.Fail("unexpected record (op " + std::to_string(inner_op) +
                           ") inside a chunk (expected connection or message records)");
      }
      inner += record.size;
    }
  }

  // Parses one record (at `location`) from `bytes` starting at `offset`.
  ParsedRecord ParseInBuffer(std::span<const uint8_t> bytes, size_t offset,
                             const std::string& location) const {
    const auto fail = [&](const std::string& what) -> ParsedRecord {
      throw InputError(p_, 0, location + ": " + what);
    };
    if (bytes.size() - offset < 4) return fail("a record header length needs 4 bytes");
    const uint32_t header_length = LoadU32(bytes.data() + offset);
    if (header_length > bytes.size() - offset - 4) {
      return fail("record header of " + std::to_string(header_length) +
                  " bytes overruns the chunk (" + std::to_string(bytes.size() - offset - 4) +
                  " left)");
    }
    HeaderFields fields;
    const std::string problem =
        ParseHeaderFields(bytes.subspan(offset + 4, header_length), &fields);
    if (!problem.empty()) return fail(problem);
    const size_t data_length_at = offset + 4 + header_length;
    if (bytes.size() - data_length_at < 4) return fail("a record data length needs 4 bytes");
    const uint32_t data_length = LoadU32(bytes.data() + data_length_at);
    if (data_length > bytes.size() - data_length_at - 4) {
      return fail("record data of " + std::to_string(data_length) + " bytes overruns the chunk (" +
                  std::to_string(bytes.size() - data_length_at - 4) + " left)");
    }
    return {RecordHeader(std::move(fields), p_, location),
            bytes.subspan(data_length_at + 4, data_length),
            8 + size_t{header_length} + data_length};
  }

  RosbagReader& reader_;
  Scan& scan_;
  const std::string p_;
  std::vector<uint8_t> header_bytes_;
  std::vector<uint8_t> data_bytes_;
};

void RosbagReader::ScanRecords(Scan& scan) {
  RecordScanner(*this, scan).Run();
}

void RosbagReader::ReadMessages(const std::function<bool(const RosbagConnection&)>& wanted,
                                const std::function<void(const RosbagMessage&)>& visit) {
  Scan scan;
  scan.messages = true;
  scan.count = false;
  scan.wanted = wanted;
  scan.visit = visit;
  ScanRecords(scan);
}

// ----------------------------------------------------------------------------
// Writer

RosbagWriter::RosbagWriter(const fs::path& path, const RosbagWriterOptions& options)
    : path_(path), options_(options) {
  temp_path_ = path;
  temp_path_ += ".tmp-" + std::to_string(::getpid());
  file_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!file_) throw InputError(path.string(), 0, "cannot write the bag (is the folder writable?)");
  WriteBytes(kRosbagVersionLine);
  // A placeholder bag header, rewritten by Close().
  WriteBytes(std::string(kBagHeaderRecordBytes, ' '));
}

RosbagWriter::~RosbagWriter() {
  if (!closed_) {
    file_.close();
    std::error_code ignored;
    fs::remove(temp_path_, ignored);
  }
}

void RosbagWriter::WriteBytes(const std::string& bytes) {
  file_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!file_) throw InputError(path_.string(), 0, "cannot write the bag (disk full?)");
  position_ += bytes.size();
}

uint32_t RosbagWriter::AddConnection(const std::string& topic, const std::string& type,
                                     const std::string& md5sum,
                                     const std::string& message_definition) {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  const uint32_t id = static_cast<uint32_t>(connections_.size());
  const std::string connection_header = EncodeHeader({{"topic", topic},
                                                      {"type", type},
                                                      {"md5sum", md5sum},
                                                      {"message_definition", message_definition}});
  Connection connection;
  connection.topic = topic;
  connection.record = EncodeRecord({{"op", std::string(1, static_cast<char>(kOpConnection))},
                                    {"conn", U32Bytes(id)},
                                    {"topic", topic}},
                                   connection_header);
  connections_.push_back(std::move(connection));
  return id;
}

void RosbagWriter::Write(uint32_t connection_id, timestamp_ns_t time_ns,
                         std::span<const uint8_t> data) {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  VIOSFM_CHECK_LT(connection_id, connections_.size());
  if (time_ns < 0 || time_ns / 1'000'000'000 > 0xffffffffLL) {
    throw InputError(
        path_.string(), 0,
        "message time " + std::to_string(time_ns) + " ns is outside ROS time (0 to 2^32 s)");
  }
  Connection& connection = connections_[connection_id];
  if (!connection.written_in_chunk) {
    chunk_data_ += connection.record;
    connection.written_in_chunk = true;
  }
  if (chunk_.counts.empty()) {
    chunk_.start_ns = time_ns;
    chunk_.end_ns = time_ns;
  }
  chunk_.start_ns = std::min(chunk_.start_ns, time_ns);
  chunk_.end_ns = std::max(chunk_.end_ns, time_ns);
  ++chunk_.counts[connection_id];
  chunk_index_[connection_id].emplace_back(time_ns, static_cast<uint32_t>(chunk_data_.size()));
  chunk_data_ +=
      EncodeRecord({{"op", std::string(1, static_cast<char>(kOpMessageData))},
                    {"conn", U32Bytes(connection_id)},
                    {"time", TimeBytes(time_ns)}},
                   std::string_view(reinterpret_cast<const char*>(data.data()), data.size()));
  if (chunk_data_.size() >= options_.chunk_threshold_bytes) FlushChunk();
}

void RosbagWriter::FlushChunk() {
  if (chunk_.counts.empty()) return;
  VIOSFM_CHECK_LE(chunk_data_.size(), 0xffffffffu) << "chunk too large";
  chunk_.position = position_;
  std::string compressed;
  const std::string compression = RosbagCompressionName(options_.compression);
  if (options_.compression == RosbagCompression::kBz2) {
    unsigned int size =
        static_cast<unsigned int>(chunk_data_.size() + chunk_data_.size() / 100 + 600);
    compressed.resize(size);
    const int status =
        BZ2_bzBuffToBuffCompress(compressed.data(), &size, chunk_data_.data(),
                                 static_cast<unsigned int>(chunk_data_.size()), 9, 0, 0);
    VIOSFM_CHECK_EQ(status, BZ_OK) << "bzip2 compression failed";
    compressed.resize(size);
  } else if (options_.compression == RosbagCompression::kLz4) {
    // ROS's own decompressor (roslz4) reads only frames with independent
    // blocks, a content checksum, no block checksums and no content size.
    LZ4F_preferences_t preferences = LZ4F_INIT_PREFERENCES;
    preferences.frameInfo.blockMode = LZ4F_blockIndependent;
    preferences.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
    preferences.frameInfo.blockSizeID = LZ4F_max1MB;
    compressed.resize(LZ4F_compressFrameBound(chunk_data_.size(), &preferences));
    const size_t size = LZ4F_compressFrame(compressed.data(), compressed.size(), chunk_data_.data(),
                                           chunk_data_.size(), &preferences);
    VIOSFM_CHECK(!LZ4F_isError(size)) << "lz4 compression failed: " << LZ4F_getErrorName(size);
    compressed.resize(size);
  }
  const std::string& payload =
      options_.compression == RosbagCompression::kNone ? chunk_data_ : compressed;
  WriteBytes(EncodeRecord({{"op", std::string(1, static_cast<char>(kOpChunkRecord))},
                           {"compression", compression},
                           {"size", U32Bytes(static_cast<uint32_t>(chunk_data_.size()))}},
                          payload));
  for (const auto& [connection_id, entries] : chunk_index_) {
    std::string data;
    for (const auto& [time_ns, offset] : entries) {
      data += TimeBytes(time_ns);
      AppendU32(data, offset);
    }
    WriteBytes(EncodeRecord({{"op", std::string(1, static_cast<char>(kOpIndexData))},
                             {"ver", U32Bytes(1)},
                             {"conn", U32Bytes(connection_id)},
                             {"count", U32Bytes(static_cast<uint32_t>(entries.size()))}},
                            data));
  }
  chunks_.push_back(chunk_);
  chunk_ = ChunkInfo{};
  chunk_data_.clear();
  chunk_index_.clear();
}

void RosbagWriter::Close() {
  VIOSFM_CHECK(!closed_) << "bag already closed";
  FlushChunk();
  const uint64_t index_pos = position_;
  for (const Connection& connection : connections_) WriteBytes(connection.record);
  for (const ChunkInfo& chunk : chunks_) {
    std::string data;
    for (const auto& [connection_id, count] : chunk.counts) {
      AppendU32(data, connection_id);
      AppendU32(data, count);
    }
    WriteBytes(EncodeRecord({{"op", std::string(1, static_cast<char>(kOpChunkInfo))},
                             {"ver", U32Bytes(1)},
                             {"chunk_pos", U64Bytes(chunk.position)},
                             {"start_time", TimeBytes(chunk.start_ns)},
                             {"end_time", TimeBytes(chunk.end_ns)},
                             {"count", U32Bytes(static_cast<uint32_t>(chunk.counts.size()))}},
                            data));
  }
  // The bag header, padded with spaces to kBagHeaderRecordBytes.
  const std::string header =
      EncodeHeader({{"op", std::string(1, static_cast<char>(kOpBagHeader))},
                    {"index_pos", U64Bytes(index_pos)},
                    {"conn_count", U32Bytes(static_cast<uint32_t>(connections_.size()))},
                    {"chunk_count", U32Bytes(static_cast<uint32_t>(chunks_.size()))}});
  const size_t padding = kBagHeaderRecordBytes - 8 - header.size();
  std::string record;
  AppendU32(record, static_cast<uint32_t>(header.size()));
  record += header;
  AppendU32(record, static_cast<uint32_t>(padding));
  record += std::string(padding, ' ');
  VIOSFM_CHECK_EQ(record.size(), kBagHeaderRecordBytes);
  file_.seekp(static_cast<std::streamoff>(sizeof(kRosbagVersionLine) - 1));
  file_.write(record.data(), static_cast<std::streamsize>(record.size()));
  file_.close();
  if (!file_) throw InputError(path_.string(), 0, "cannot write the bag (disk full?)");
  std::error_code error;
  fs::rename(temp_path_, path_, error);
  if (error) {
    fs::remove(temp_path_, error);
    throw InputError(path_.string(), 0, "cannot rename the temporary bag: " + error.message());
  }
  closed_ = true;
}

}  // namespace viosfm

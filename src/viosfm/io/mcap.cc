#include "viosfm/io/mcap.h"

#include <unistd.h>

#include <array>
#include <cstring>
#include <limits>
#include <optional>
#include <system_error>

#include "viosfm/io/bag_bytes.h"
#include "viosfm/io/compression.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

constexpr uint8_t kOpHeader = 0x01;
constexpr uint8_t kOpFooter = 0x02;
constexpr uint8_t kOpSchema = 0x03;
constexpr uint8_t kOpChannel = 0x04;
constexpr uint8_t kOpMessage = 0x05;
constexpr uint8_t kOpChunk = 0x06;
constexpr uint8_t kOpMessageIndex = 0x07;
constexpr uint8_t kOpChunkIndex = 0x08;
constexpr uint8_t kOpStatistics = 0x0b;
constexpr uint8_t kOpSummaryOffset = 0x0e;
constexpr uint8_t kOpDataEnd = 0x0f;
constexpr uint64_t kRecordPrefixBytes = 9;  // opcode + uint64 length
constexpr uint64_t kFooterContentBytes = 20;
constexpr uint64_t kMagicBytes = sizeof(kMcapMagic);
// Largest uncompressed chunk accepted (rosbag2 writes chunks of about 768 KiB;
// one image larger than that makes a chunk of its own).
constexpr uint64_t kMaxChunkBytes = uint64_t{1} << 30;

std::string OpName(uint8_t op) {
  static const std::array<const char*, 16> kNames = {
      "unknown",          "header",     "footer",        "schema",         "channel",
      "message",          "chunk",      "message index", "chunk index",    "attachment",
      "attachment index", "statistics", "metadata",      "metadata index", "summary offset",
      "data end"};
  if (op < kNames.size()) return kNames[op];
  return "op 0x" + std::string(1, "0123456789abcdef"[op >> 4]) + "0123456789abcdef"[op & 15];
}

// The fields of one record's content, read in order; every overrun names
// the file, the record's location and the field.
class Fields {
 public:
  Fields(std::span<const uint8_t> content, const std::string& path, const std::string& location,
         uint8_t op)
      : content_(content), path_(path), location_(location), op_(op) {}

  uint8_t U8(const char* field) { return static_cast<uint8_t>(Unsigned(1, field)); }
  uint16_t U16(const char* field) { return static_cast<uint16_t>(Unsigned(2, field)); }
  uint32_t U32(const char* field) { return static_cast<uint32_t>(Unsigned(4, field)); }
  uint64_t U64(const char* field) { return Unsigned(8, field); }
  timestamp_ns_t Time(const char* field) {
    const uint64_t value = U64(field);
    if (value > static_cast<uint64_t>(std::numeric_limits<timestamp_ns_t>::max())) {
      Fail(std::string(field) + " is " + std::to_string(value) + " ns, past 2262");
    }
    return static_cast<timestamp_ns_t>(value);
  }
  std::span<const uint8_t> Bytes32(const char* field) { return Take(U32(field), field); }
  std::span<const uint8_t> Bytes64(const char* field) { return Take(U64(field), field); }
  std::string String(const char* field) {
    const std::span<const uint8_t> bytes = Bytes32(field);
    return std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  std::map<std::string, std::string> StringMap(const char* field) {
    Fields entries(Bytes32(field), path_, location_, op_);
    std::map<std::string, std::string> map;
    while (!entries.AtEnd()) {
      std::string key = entries.String(field);
      map[key] = entries.String(field);
    }
    return map;
  }
  std::span<const uint8_t> Rest() { return Take(content_.size() - offset_, "data"); }
  bool AtEnd() const { return offset_ == content_.size(); }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_, 0, location_ + ": " + OpName(op_) + " record: " + what);
  }

 private:
  uint64_t Unsigned(size_t size, const char* field) {
    const std::span<const uint8_t> bytes = Take(size, field);
    uint64_t value = 0;
    for (size_t i = size; i-- > 0;) value = (value << 8) | bytes[i];
    return value;
  }
  std::span<const uint8_t> Take(uint64_t size, const char* field) {
    if (size > content_.size() - offset_) {
      Fail(std::string(field) + " needs " + std::to_string(size) + " bytes, " +
           std::to_string(content_.size() - offset_) + " left in the record (" +
           std::to_string(content_.size()) + " bytes)");
    }
    const std::span<const uint8_t> out = content_.subspan(offset_, size);
    offset_ += size;
    return out;
  }

  std::span<const uint8_t> content_;
  size_t offset_ = 0;
  const std::string& path_;
  const std::string& location_;
  uint8_t op_;
};

void AppendU16(std::string& out, uint16_t value) {
  for (int i = 0; i < 2; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}
void AppendString(std::string& out, const std::string& text) {
  VIOSFM_CHECK_LE(text.size(), 0xffffffffu) << "MCAP string too long";
  AppendU32(out, static_cast<uint32_t>(text.size()));
  out += text;
}
std::string EncodeRecord(uint8_t op, const std::string& content) {
  std::string record;
  record.reserve(kRecordPrefixBytes + content.size());
  record.push_back(static_cast<char>(op));
  AppendU64(record, content.size());
  record += content;
  return record;
}
std::span<const uint8_t> AsBytes(const std::string& text) {
  return std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

}  // namespace

uint32_t Crc32(std::span<const uint8_t> data, uint32_t crc) {
  static const std::array<uint32_t, 256> kTable = [] {
    std::array<uint32_t, 256> table{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t value = i;
      for (int bit = 0; bit < 8; ++bit)
        value = (value & 1) ? 0xedb88320u ^ (value >> 1) : value >> 1;
      table[i] = value;
    }
    return table;
  }();
  crc = ~crc;
  for (const uint8_t byte : data) crc = kTable[(crc ^ byte) & 0xff] ^ (crc >> 8);
  return ~crc;
}

std::string McapCompressionName(McapCompression compression) {
  switch (compression) {
    case McapCompression::kNone: return "";
    case McapCompression::kZstd: return "zstd";
    case McapCompression::kLz4: return "lz4";
  }
  return "";
}

// ----------------------------------------------------------------------------
// Reader

struct McapReader::Scan {
  bool messages = false;  // decode message records (false: channels only)
  bool count = false;     // count messages per channel
  // Read up to here (the footer, or the file's end for a truncated file).
  uint64_t end = 0;
  std::function<bool(const McapChannel&)> wanted;
  std::function<void(const McapMessage&)> visit;
};

namespace {}  // namespace

McapReader::McapReader(const fs::path& path) : path_(path) {
  const std::string p = path.string();
  std::error_code error;
  if (!fs::is_regular_file(path, error)) throw InputError(p, 0, "MCAP file not found");
  file_size_ = fs::file_size(path, error);
  file_.open(path, std::ios::binary);
  if (error || !file_) throw InputError(p, 0, "cannot open the MCAP file");

  uint8_t magic[kMagicBytes] = {};
  const uint64_t leading = std::min<uint64_t>(file_size_, kMagicBytes);
  ReadAt(file_, p, file_size_, 0, magic, leading, "magic", "file");
  if (leading < kMagicBytes || std::memcmp(magic, kMcapMagic, 5) != 0) {
    throw InputError(p, 0,
                     "not an MCAP file: expected the magic bytes 89 'MCAP' '0' '\\r' '\\n' at "
                     "byte offset 0");
  }
  if (std::memcmp(magic, kMcapMagic, kMagicBytes) != 0) {
    throw InputError(p, 0,
                     "MCAP major version '" + std::string(1, static_cast<char>(magic[5])) +
                         "' is not read (expected '0', the published specification)");
  }

  // The Header record.
  uint8_t prefix[kRecordPrefixBytes];
  ReadAt(file_, p, file_size_, kMagicBytes, prefix, kRecordPrefixBytes, "header record", "file");
  const uint64_t header_length = LoadU64(prefix + 1);
  if (prefix[0] != kOpHeader) {
    throw InputError(p, 0,
                     ByteOffset(kMagicBytes) +
                         ": expected the header record (op 0x01) after the "
                         "magic, found " +
                         OpName(prefix[0]));
  }
  if (header_length > file_size_ - kMagicBytes - kRecordPrefixBytes) {
    throw InputError(p, 0,
                     ByteOffset(kMagicBytes) + ": header record of " +
                         std::to_string(header_length) + " bytes, the file ends first (truncated)");
  }
  std::vector<uint8_t> header(header_length);
  ReadAt(file_, p, file_size_, kMagicBytes + kRecordPrefixBytes, header.data(), header_length,
         "header record", "file");
  const std::string header_location = ByteOffset(kMagicBytes);
  Fields header_fields(header, p, header_location, kOpHeader);
  profile_ = header_fields.String("profile");
  library_ = header_fields.String("library");

  ReadFooter();
  if (summary_start_ != 0) ReadSummary();
  const bool counted = !channels_.empty() && std::any_of(channels_.begin(), channels_.end(),
                                                         [](const McapChannel& channel) {
                                                           return channel.num_messages > 0;
                                                         });
  if (summary_start_ == 0 || !counted) {
    // No summary (or one without message counts): scan the file.
    for (McapChannel& channel : channels_) channel.num_messages = 0;
    Scan scan;
    scan.count = true;
    scan.end = footer_offset_;
    ScanData(scan);
  }
}

void McapReader::ReadFooter() {
  const std::string p = path_.string();
  const uint64_t tail = kRecordPrefixBytes + kFooterContentBytes + kMagicBytes;
  uint8_t closing[kMagicBytes] = {};
  const bool has_closing = file_size_ >= kMagicBytes + tail;
  if (has_closing) {
    ReadAt(file_, p, file_size_, file_size_ - kMagicBytes, closing, kMagicBytes, "closing magic",
           "file");
  }
  if (!has_closing || std::memcmp(closing, kMcapMagic, kMagicBytes) != 0) {
    // Find where the file was cut: a scan of its records throws at the
    // first one that runs past the end.
    Scan scan;
    scan.count = true;
    scan.end = file_size_;
    ScanData(scan);
    throw InputError(p, 0,
                     "the file ends without the footer record and the closing magic bytes (the "
                     "file is truncated: a recording that was interrupted? `mcap recover` "
                     "rewrites what it holds)");
  }
  footer_offset_ = file_size_ - tail;
  uint8_t footer[kRecordPrefixBytes + kFooterContentBytes];
  ReadAt(file_, p, file_size_, footer_offset_, footer, sizeof(footer), "footer record", "file");
  if (footer[0] != kOpFooter || LoadU64(footer + 1) != kFooterContentBytes) {
    throw InputError(p, 0,
                     ByteOffset(footer_offset_) +
                         ": expected the footer record (op 0x02, 20 bytes) before the closing "
                         "magic (the file is truncated or corrupt)");
  }
  summary_start_ = LoadU64(footer + 9);
  summary_offset_start_ = LoadU64(footer + 17);
  summary_crc_ = static_cast<uint32_t>(footer[25]) | (static_cast<uint32_t>(footer[26]) << 8) |
                 (static_cast<uint32_t>(footer[27]) << 16) |
                 (static_cast<uint32_t>(footer[28]) << 24);
  const uint64_t data_start = kMagicBytes + kRecordPrefixBytes;
  if ((summary_start_ != 0 && (summary_start_ < data_start || summary_start_ > footer_offset_)) ||
      (summary_offset_start_ != 0 &&
       (summary_offset_start_ < summary_start_ || summary_offset_start_ > footer_offset_))) {
    throw InputError(p, 0,
                     ByteOffset(footer_offset_) + ": footer record: summary at byte offset " +
                         std::to_string(summary_start_) + ", summary offsets at " +
                         std::to_string(summary_offset_start_) + ": outside the file's " +
                         std::to_string(file_size_) + " bytes");
  }
  if (summary_start_ != 0 && summary_crc_ != 0) {
    const uint64_t size = footer_offset_ + kRecordPrefixBytes + 16 - summary_start_;
    std::vector<uint8_t> bytes(size);
    ReadAt(file_, p, file_size_, summary_start_, bytes.data(), size, "summary section", "file");
    const uint32_t crc = Crc32(bytes);
    if (crc != summary_crc_) {
      throw InputError(p, 0,
                       "the summary section (byte offset " + std::to_string(summary_start_) +
                           " to the footer) has CRC " + std::to_string(crc) +
                           ", the footer states " + std::to_string(summary_crc_) +
                           " (the file is corrupt)");
    }
  }
}

void McapReader::ReadSummary() {
  const std::string p = path_.string();
  const uint64_t end = summary_offset_start_ != 0 ? summary_offset_start_ : footer_offset_;
  std::vector<uint8_t> bytes(end - summary_start_);
  ReadAt(file_, p, file_size_, summary_start_, bytes.data(), bytes.size(), "summary section",
         "file");
  struct Found {
    uint8_t op;
    std::span<const uint8_t> content;
    std::string location;
  };
  std::vector<Found> records;
  size_t offset = 0;
  while (offset < bytes.size()) {
    const std::string location = ByteOffset(summary_start_ + offset);
    if (bytes.size() - offset < kRecordPrefixBytes) {
      throw InputError(p, 0, location + ": a record prefix needs 9 bytes, the summary ends first");
    }
    const uint8_t op = bytes[offset];
    const uint64_t length = LoadU64(bytes.data() + offset + 1);
    if (length > bytes.size() - offset - kRecordPrefixBytes) {
      throw InputError(p, 0,
                       location + ": " + OpName(op) + " record of " + std::to_string(length) +
                           " bytes runs past the summary section");
    }
    records.push_back({op,
                       std::span<const uint8_t>(bytes).subspan(offset + kRecordPrefixBytes, length),
                       location});
    offset += kRecordPrefixBytes + length;
  }
  // Schemas first: a channel names its schema by id.
  for (const Found& record : records) {
    if (record.op != kOpSchema) continue;
    Fields fields(record.content, p, record.location, record.op);
    const uint16_t id = fields.U16("id");
    std::string name = fields.String("name");
    std::string encoding = fields.String("encoding");
    const std::span<const uint8_t> data = fields.Bytes32("data");
    AddSchema(id, std::move(name), std::move(encoding),
              std::string(reinterpret_cast<const char*>(data.data()), data.size()),
              record.location);
  }
  std::map<uint16_t, uint64_t> counts;
  for (const Found& record : records) {
    Fields fields(record.content, p, record.location, record.op);
    if (record.op == kOpChannel) {
      McapChannel channel;
      channel.id = fields.U16("id");
      channel.schema_id = fields.U16("schema_id");
      channel.topic = fields.String("topic");
      channel.message_encoding = fields.String("message_encoding");
      channel.metadata = fields.StringMap("metadata");
      AddChannel(std::move(channel), record.location);
    } else if (record.op == kOpStatistics) {
      fields.U64("message_count");
      fields.U16("schema_count");
      fields.U32("channel_count");
      fields.U32("attachment_count");
      fields.U32("metadata_count");
      fields.U32("chunk_count");
      fields.Time("message_start_time");
      fields.Time("message_end_time");
      Fields entries(fields.Bytes32("channel_message_counts"), p, record.location, record.op);
      while (!entries.AtEnd()) {
        const uint16_t id = entries.U16("channel_message_counts");
        counts[id] = entries.U64("channel_message_counts");
      }
    }
  }
  for (const auto& [id, count] : counts) {
    const auto it = channel_index_.find(id);
    if (it == channel_index_.end()) {
      throw InputError(p, 0,
                       "summary: the statistics count messages on channel " + std::to_string(id) +
                           ", which the summary does not define");
    }
    channels_[it->second].num_messages = count;
  }
}

void McapReader::AddSchema(uint16_t id, std::string name, std::string encoding, std::string data,
                           const std::string& location) {
  if (id == 0) return;  // invalid by the specification: ignored
  const auto existing = schemas_.find(id);
  if (existing != schemas_.end()) {
    if (existing->second.name != name || existing->second.encoding != encoding ||
        existing->second.data != data) {
      throw InputError(path_.string(), 0,
                       location + ": schema " + std::to_string(id) +
                           " is defined twice, differently ('" + existing->second.name + "', '" +
                           name + "')");
    }
    return;
  }
  schemas_[id] = {std::move(name), std::move(encoding), std::move(data)};
}

void McapReader::AddChannel(McapChannel channel, const std::string& location) {
  const std::string p = path_.string();
  if (channel.schema_id != 0) {
    const auto schema = schemas_.find(channel.schema_id);
    if (schema == schemas_.end()) {
      throw InputError(p, 0,
                       location + ": channel " + std::to_string(channel.id) + " ('" +
                           channel.topic + "') refers to schema " +
                           std::to_string(channel.schema_id) +
                           ", which no schema record before "
                           "it defines");
    }
    channel.schema_name = schema->second.name;
    channel.schema_encoding = schema->second.encoding;
    channel.schema_data = schema->second.data;
  }
  const auto existing = channel_index_.find(channel.id);
  if (existing != channel_index_.end()) {
    const McapChannel& known = channels_[existing->second];
    if (known.topic != channel.topic || known.message_encoding != channel.message_encoding ||
        known.schema_id != channel.schema_id) {
      throw InputError(p, 0,
                       location + ": channel " + std::to_string(channel.id) +
                           " is defined twice, differently ('" + known.topic + "' " +
                           known.schema_name + ", '" + channel.topic + "' " + channel.schema_name +
                           ")");
    }
    return;
  }
  const auto position =
      std::lower_bound(channels_.begin(), channels_.end(), channel.id,
                       [](const McapChannel& c, uint16_t id) { return c.id < id; });
  channels_.insert(position, std::move(channel));
  channel_index_.clear();
  for (size_t i = 0; i < channels_.size(); ++i) channel_index_[channels_[i].id] = i;
}

// The data section's records in order, each handed to the step its op
// names: schemas, channels, messages, and chunks (decompressed, their CRC
// checked, their records handed on in turn); the data section's CRC is
// checked at its end.
class McapReader::RecordScanner {
 public:
  RecordScanner(McapReader& reader, Scan& scan)
      : reader_(reader), scan_(scan), p_(reader.path_.string()) {}

  void Run() {
    // The header record was read by the constructor.
    uint8_t prefix[kRecordPrefixBytes];
    ReadAt(reader_.file_, p_, reader_.file_size_, kMagicBytes, prefix, kRecordPrefixBytes,
           "header record", "file");
    uint64_t offset = kMagicBytes + kRecordPrefixBytes + LoadU64(prefix + 1);
    std::vector<uint8_t> magic_and_header(offset);
    ReadAt(reader_.file_, p_, reader_.file_size_, 0, magic_and_header.data(), offset,
           "header record", "file");
    crc_ = Crc32(magic_and_header);
    while (offset < scan_.end) {
      const std::optional<uint64_t> next = ScanRecordAt(offset);
      if (!next) return;
      offset = *next;
    }
  }

 private:
  // Reads the record at `offset` and takes it; returns the next record's
  // offset, or none after the data end record.
  std::optional<uint64_t> ScanRecordAt(uint64_t offset) {
    const std::string location = ByteOffset(offset);
    const uint64_t end = scan_.end;
    if (end - offset < kRecordPrefixBytes) {
      throw InputError(p_, 0,
                       location + ": a record prefix needs 9 bytes, " +
                           std::to_string(end - offset) +
                           " left before the footer (the file is truncated or corrupt)");
    }
    uint8_t prefix[kRecordPrefixBytes];
    ReadAt(reader_.file_, p_, reader_.file_size_, offset, prefix, kRecordPrefixBytes,
           "record prefix", "file");
    const uint8_t op = prefix[0];
    const uint64_t length = LoadU64(prefix + 1);
    if (length > end - offset - kRecordPrefixBytes) {
      throw InputError(p_, 0,
                       location + ": " + OpName(op) + " record of " + std::to_string(length) +
                           " bytes, the " +
                           (end == reader_.file_size_ ? std::string("file ends after ")
                                                      : std::string("footer comes after ")) +
                           std::to_string(end - offset - kRecordPrefixBytes) +
                           " (the file is truncated or corrupt)");
    }
    if (op == kOpDataEnd) {
      CheckDataEnd(offset, length, location);
      return std::nullopt;
    }
    if (op == kOpFooter) {
      throw InputError(p_, 0, location + ": footer record inside the file (expected data records)");
    }
    record_.resize(kRecordPrefixBytes + length);
    ReadAt(reader_.file_, p_, reader_.file_size_, offset, record_.data(), record_.size(),
           OpName(op) + " record", "file");
    crc_ = Crc32(record_, crc_);
    const std::span<const uint8_t> content =
        std::span<const uint8_t>(record_).subspan(kRecordPrefixBytes);
    if (op == kOpHeader) {
      throw InputError(p_, 0, location + ": a second header record");
    } else if (op == kOpChunk) {
      TakeChunk(content, location);
    } else {
      // Message indexes, attachments, metadata and records of later
      // versions of the format are not needed.
      TakeRecord(op, content, location, /*in_chunk=*/false);
    }
    return offset + kRecordPrefixBytes + length;
  }

  // The data end record's CRC of the data section, if it states one.
  void CheckDataEnd(uint64_t offset, uint64_t length, const std::string& location) {
    record_.resize(length);
    ReadAt(reader_.file_, p_, reader_.file_size_, offset + kRecordPrefixBytes, record_.data(),
           length, "data end record", "file");
    Fields data_end(record_, p_, location, kOpDataEnd);
    const uint32_t stated = data_end.U32("data_section_crc");
    if (stated != 0 && stated != crc_) {
      data_end.Fail("the data section's CRC is " + std::to_string(crc_) + ", the record states " +
                    std::to_string(stated) + " (the file is corrupt)");
    }
  }

  // A schema, channel or message record; inside a chunk anything else is an
  // error, outside it is skipped.
  void TakeRecord(uint8_t op, std::span<const uint8_t> content, const std::string& location,
                  bool in_chunk) {
    if (op == kOpSchema) {
      TakeSchema(content, location);
    } else if (op == kOpChannel) {
      TakeChannel(content, location);
    } else if (op == kOpMessage) {
      TakeMessage(content, location);
    } else if (in_chunk) {
      throw InputError(p_, 0,
                       location + ": " + OpName(op) +
                           " record inside a chunk (a chunk holds schema, channel and message "
                           "records)");
    }
  }

  void TakeSchema(std::span<const uint8_t> content, const std::string& location) {
    Fields fields(content, p_, location, kOpSchema);
    const uint16_t id = fields.U16("id");
    std::string name = fields.String("name");
    std::string encoding = fields.String("encoding");
    const std::span<const uint8_t> data = fields.Bytes32("data");
    reader_.AddSchema(id, std::move(name), std::move(encoding),
                      std::string(reinterpret_cast<const char*>(data.data()), data.size()),
                      location);
  }

  void TakeChannel(std::span<const uint8_t> content, const std::string& location) {
    Fields fields(content, p_, location, kOpChannel);
    McapChannel channel;
    channel.id = fields.U16("id");
    channel.schema_id = fields.U16("schema_id");
    channel.topic = fields.String("topic");
    channel.message_encoding = fields.String("message_encoding");
    channel.metadata = fields.StringMap("metadata");
    reader_.AddChannel(std::move(channel), location);
  }

  void TakeMessage(std::span<const uint8_t> content, const std::string& location) {
    Fields fields(content, p_, location, kOpMessage);
    McapMessage message;
    const uint16_t channel_id = fields.U16("channel_id");
    message.sequence = fields.U32("sequence");
    message.log_time_ns = fields.Time("log_time");
    message.publish_time_ns = fields.Time("publish_time");
    message.data = fields.Rest();
    const auto it = reader_.channel_index_.find(channel_id);
    if (it == reader_.channel_index_.end()) {
      fields.Fail("message on channel " + std::to_string(channel_id) +
                  ", which no channel record before it defines");
    }
    McapChannel& channel = reader_.channels_[it->second];
    if (scan_.count) ++channel.num_messages;
    if (!scan_.messages || !scan_.wanted(channel)) return;
    message.channel = &channel;
    message.location = location;
    scan_.visit(message);
  }

  void TakeChunk(std::span<const uint8_t> content, const std::string& location) {
    Fields fields(content, p_, location, kOpChunk);
    fields.Time("message_start_time");
    fields.Time("message_end_time");
    const uint64_t uncompressed_size = fields.U64("uncompressed_size");
    const uint32_t crc = fields.U32("uncompressed_crc");
    const std::string compression = fields.String("compression");
    const std::span<const uint8_t> stored = fields.Bytes64("records");
    if (uncompressed_size > kMaxChunkBytes) {
      fields.Fail("states " + std::to_string(uncompressed_size) +
                  " uncompressed bytes (more than 1 GiB: a corrupt record?)");
    }
    const std::string where = p_ + ": " + location + " (chunk, " +
                              (compression.empty() ? "uncompressed" : compression) + ")";
    std::vector<uint8_t> decompressed;
    std::span<const uint8_t> records = stored;
    if (compression == "zstd") {
      decompressed = DecompressZstd(stored, uncompressed_size, kMaxChunkBytes, where);
      records = decompressed;
    } else if (compression == "lz4") {
      decompressed = DecompressLz4Frame(stored, uncompressed_size, where);
      records = decompressed;
    } else if (!compression.empty()) {
      fields.Fail("compression '" + compression + "' is not read (expected none, zstd or lz4)");
    } else if (stored.size() != uncompressed_size) {
      fields.Fail("uncompressed records of " + std::to_string(stored.size()) +
                  " bytes, the record states " + std::to_string(uncompressed_size));
    }
    if (crc != 0) {
      const uint32_t computed = Crc32(records);
      if (computed != crc) {
        fields.Fail("the records' CRC is " + std::to_string(computed) + ", the chunk states " +
                    std::to_string(crc) + " (the chunk is corrupt)");
      }
    }
    TakeChunkRecords(records, location + (compression.empty() ? "" : " (" + compression + ")"));
  }

  // The records of a chunk's (decompressed) records section.
  void TakeChunkRecords(std::span<const uint8_t> records, const std::string& chunk_location) {
    size_t offset = 0;
    while (offset < records.size()) {
      const std::string inner_location =
          "chunk at " + chunk_location + ", offset " + std::to_string(offset) + " of its records";
      if (records.size() - offset < kRecordPrefixBytes) {
        throw InputError(p_, 0, inner_location + ": a record prefix needs 9 bytes, the chunk ends");
      }
      const uint8_t op = records[offset];
      const uint64_t length = LoadU64(records.data() + offset + 1);
      if (length > records.size() - offset - kRecordPrefixBytes) {
        throw InputError(p_, 0,
                         inner_location + ": " + OpName(op) + " record of " +
                             std::to_string(length) + " bytes runs past the chunk's records (" +
                             std::to_string(records.size() - offset - kRecordPrefixBytes) +
                             " left)");
      }
      TakeRecord(op, records.subspan(offset + kRecordPrefixBytes, length), inner_location,
                 /*in_chunk=*/true);
      offset += kRecordPrefixBytes + length;
    }
  }

  McapReader& reader_;
  Scan& scan_;
  const std::string p_;
  std::vector<uint8_t> record_;
  uint32_t crc_ = 0;
};

void McapReader::ScanData(Scan& scan) {
  RecordScanner(*this, scan).Run();
}

void McapReader::ReadMessages(const std::function<bool(const McapChannel&)>& wanted,
                              const std::function<void(const McapMessage&)>& visit) {
  Scan scan;
  scan.messages = true;
  scan.end = footer_offset_;
  scan.wanted = wanted;
  scan.visit = visit;
  ScanData(scan);
}

// ----------------------------------------------------------------------------
// Writer

McapWriter::McapWriter(const fs::path& path, const McapWriterOptions& options)
    : path_(path), options_(options) {
  VIOSFM_CHECK_GT(options.chunk_threshold_bytes, 0u);
  temp_path_ = path;
  temp_path_ += ".tmp-" + std::to_string(::getpid());
  file_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!file_) throw InputError(path.string(), 0, "cannot write the file (is the folder writable?)");
  WriteBytes(std::string(reinterpret_cast<const char*>(kMcapMagic), kMagicBytes));
  std::string header;
  AppendString(header, options_.profile);
  AppendString(header, "viosfm");
  WriteBytes(EncodeRecord(kOpHeader, header));
}

McapWriter::~McapWriter() {
  if (!closed_) {
    file_.close();
    std::error_code ignored;
    fs::remove(temp_path_, ignored);
  }
}

void McapWriter::WriteBytes(const std::string& bytes) {
  file_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!file_) throw InputError(path_.string(), 0, "cannot write the file (disk full?)");
  if (in_data_section_) data_crc_ = Crc32(AsBytes(bytes), data_crc_);
  position_ += bytes.size();
}

uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) {
  VIOSFM_CHECK(!closed_) << "MCAP file already closed";
  VIOSFM_CHECK_LT(schemas_.size(), 0xffffu) << "too many schemas";
  const uint16_t id = static_cast<uint16_t>(schemas_.size() + 1);
  std::string content;
  AppendU16(content, id);
  AppendString(content, name);
  AppendString(content, encoding);
  AppendString(content, data);
  schemas_.push_back({EncodeRecord(kOpSchema, content), false});
  return id;
}

uint16_t McapWriter::AddChannel(const std::string& topic, uint16_t schema_id,
                                const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  VIOSFM_CHECK(!closed_) << "MCAP file already closed";
  VIOSFM_CHECK_LE(schema_id, schemas_.size()) << "unknown schema";
  VIOSFM_CHECK_LT(channels_.size(), 0xffffu) << "too many channels";
  const uint16_t id = static_cast<uint16_t>(channels_.size() + 1);
  std::string content;
  AppendU16(content, id);
  AppendU16(content, schema_id);
  AppendString(content, topic);
  AppendString(content, message_encoding);
  std::string entries;
  for (const auto& [key, value] : metadata) {
    AppendString(entries, key);
    AppendString(entries, value);
  }
  AppendString(content, entries);
  channels_.push_back({EncodeRecord(kOpChannel, content), false});
  channel_schema_.push_back(schema_id);
  channel_sequence_.push_back(0);
  channel_count_.push_back(0);
  return id;
}

void McapWriter::Write(uint16_t channel_id, timestamp_ns_t log_time_ns,
                       timestamp_ns_t publish_time_ns, std::span<const uint8_t> data) {
  VIOSFM_CHECK(!closed_) << "MCAP file already closed";
  VIOSFM_CHECK(channel_id >= 1 && channel_id <= channels_.size()) << "unknown channel";
  VIOSFM_CHECK(log_time_ns >= 0 && publish_time_ns >= 0) << "negative MCAP time";
  const size_t index = channel_id - 1;
  if (!channels_[index].written) {
    const uint16_t schema_id = channel_schema_[index];
    if (schema_id != 0 && !schemas_[schema_id - 1].written) {
      chunk_records_ += schemas_[schema_id - 1].bytes;
      schemas_[schema_id - 1].written = true;
    }
    chunk_records_ += channels_[index].bytes;
    channels_[index].written = true;
  }
  if (chunk_messages_ == 0) {
    chunk_start_ns_ = log_time_ns;
    chunk_end_ns_ = log_time_ns;
  }
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  if (message_count_ == 0) {
    start_ns_ = log_time_ns;
    end_ns_ = log_time_ns;
  }
  start_ns_ = std::min(start_ns_, log_time_ns);
  end_ns_ = std::max(end_ns_, log_time_ns);
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_records_.size());
  std::string content;
  content.reserve(22 + data.size());
  AppendU16(content, channel_id);
  AppendU32(content, channel_sequence_[index]++);
  AppendU64(content, static_cast<uint64_t>(log_time_ns));
  AppendU64(content, static_cast<uint64_t>(publish_time_ns));
  content.append(reinterpret_cast<const char*>(data.data()), data.size());
  chunk_records_ += EncodeRecord(kOpMessage, content);
  ++chunk_messages_;
  ++message_count_;
  ++channel_count_[index];
  if (chunk_records_.size() >= options_.chunk_threshold_bytes) FlushChunk();
}

void McapWriter::FlushChunk() {
  if (chunk_records_.empty()) return;
  const std::span<const uint8_t> records = AsBytes(chunk_records_);
  std::vector<uint8_t> compressed;
  if (options_.compression == McapCompression::kZstd) {
    compressed = CompressZstd(records);
  } else if (options_.compression == McapCompression::kLz4) {
    compressed = CompressLz4Frame(records);
  }
  const std::span<const uint8_t> stored = options_.compression == McapCompression::kNone
                                              ? records
                                              : std::span<const uint8_t>(compressed);
  std::string content;
  AppendU64(content, static_cast<uint64_t>(chunk_messages_ ? chunk_start_ns_ : 0));
  AppendU64(content, static_cast<uint64_t>(chunk_messages_ ? chunk_end_ns_ : 0));
  AppendU64(content, chunk_records_.size());
  AppendU32(content, Crc32(records));
  AppendString(content, McapCompressionName(options_.compression));
  AppendU64(content, stored.size());
  content.append(reinterpret_cast<const char*>(stored.data()), stored.size());
  const uint64_t chunk_start = position_;
  const std::string chunk = EncodeRecord(kOpChunk, content);
  WriteBytes(chunk);
  ++chunk_count_;
  if (options_.summary) {
    const uint64_t index_start = position_;
    std::map<uint16_t, uint64_t> index_offsets;
    for (const auto& [channel_id, entries] : chunk_index_) {
      std::string index;
      AppendU16(index, channel_id);
      AppendU32(index, static_cast<uint32_t>(entries.size() * 16));
      for (const auto& [time_ns, offset] : entries) {
        AppendU64(index, static_cast<uint64_t>(time_ns));
        AppendU64(index, offset);
      }
      index_offsets[channel_id] = position_;
      WriteBytes(EncodeRecord(kOpMessageIndex, index));
    }
    std::string chunk_index;
    AppendU64(chunk_index, static_cast<uint64_t>(chunk_messages_ ? chunk_start_ns_ : 0));
    AppendU64(chunk_index, static_cast<uint64_t>(chunk_messages_ ? chunk_end_ns_ : 0));
    AppendU64(chunk_index, chunk_start);
    AppendU64(chunk_index, chunk.size());
    std::string offsets;
    for (const auto& [channel_id, offset] : index_offsets) {
      AppendU16(offsets, channel_id);
      AppendU64(offsets, offset);
    }
    AppendU32(chunk_index, static_cast<uint32_t>(offsets.size()));
    chunk_index += offsets;
    AppendU64(chunk_index, position_ - index_start);
    AppendString(chunk_index, McapCompressionName(options_.compression));
    AppendU64(chunk_index, stored.size());
    AppendU64(chunk_index, chunk_records_.size());
    chunk_index_records_.push_back(EncodeRecord(kOpChunkIndex, chunk_index));
  }
  chunk_records_.clear();
  chunk_index_.clear();
  chunk_messages_ = 0;
}

void McapWriter::Close() {
  VIOSFM_CHECK(!closed_) << "MCAP file already closed";
  FlushChunk();
  std::string data_end;
  AppendU32(data_end, data_crc_);
  in_data_section_ = false;
  WriteBytes(EncodeRecord(kOpDataEnd, data_end));

  uint64_t summary_start = 0;
  uint64_t summary_offset_start = 0;
  uint32_t summary_crc = 0;
  if (options_.summary) {
    summary_start = position_;
    std::string summary;
    std::vector<std::pair<uint8_t, std::pair<uint64_t, uint64_t>>> groups;
    const auto add_group = [&](uint8_t op, const std::vector<std::string>& records) {
      if (records.empty()) return;
      const uint64_t start = summary_start + summary.size();
      for (const std::string& record : records) summary += record;
      groups.push_back({op, {start, summary_start + summary.size() - start}});
    };
    std::vector<std::string> schemas, channels;
    for (const Record& schema : schemas_) schemas.push_back(schema.bytes);
    for (const Record& channel : channels_) channels.push_back(channel.bytes);
    add_group(kOpSchema, schemas);
    add_group(kOpChannel, channels);
    std::string statistics;
    AppendU64(statistics, message_count_);
    AppendU16(statistics, static_cast<uint16_t>(schemas_.size()));
    AppendU32(statistics, static_cast<uint32_t>(channels_.size()));
    AppendU32(statistics, 0);  // attachments
    AppendU32(statistics, 0);  // metadata
    AppendU32(statistics, chunk_count_);
    AppendU64(statistics, static_cast<uint64_t>(message_count_ ? start_ns_ : 0));
    AppendU64(statistics, static_cast<uint64_t>(message_count_ ? end_ns_ : 0));
    std::string counts;
    for (size_t i = 0; i < channels_.size(); ++i) {
      AppendU16(counts, static_cast<uint16_t>(i + 1));
      AppendU64(counts, channel_count_[i]);
    }
    AppendU32(statistics, static_cast<uint32_t>(counts.size()));
    statistics += counts;
    add_group(kOpStatistics, {EncodeRecord(kOpStatistics, statistics)});
    add_group(kOpChunkIndex, chunk_index_records_);
    summary_offset_start = summary_start + summary.size();
    for (const auto& [op, span] : groups) {
      std::string offset;
      offset.push_back(static_cast<char>(op));
      AppendU64(offset, span.first);
      AppendU64(offset, span.second);
      summary += EncodeRecord(kOpSummaryOffset, offset);
    }
    WriteBytes(summary);
    std::string footer_start;
    footer_start.push_back(static_cast<char>(kOpFooter));
    AppendU64(footer_start, kFooterContentBytes);
    AppendU64(footer_start, summary_start);
    AppendU64(footer_start, summary_offset_start);
    summary_crc = Crc32(AsBytes(footer_start), Crc32(AsBytes(summary)));
  }
  std::string footer;
  AppendU64(footer, summary_start);
  AppendU64(footer, summary_offset_start);
  AppendU32(footer, summary_crc);
  WriteBytes(EncodeRecord(kOpFooter, footer));
  WriteBytes(std::string(reinterpret_cast<const char*>(kMcapMagic), kMagicBytes));
  file_.close();
  if (!file_) throw InputError(path_.string(), 0, "cannot write the file (disk full?)");
  std::error_code error;
  fs::rename(temp_path_, path_, error);
  if (error) {
    fs::remove(temp_path_, error);
    throw InputError(path_.string(), 0, "cannot rename the temporary file: " + error.message());
  }
  closed_ = true;
}

}  // namespace viosfm

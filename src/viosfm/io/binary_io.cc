#include "viosfm/io/binary_io.h"

#include <ostream>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {

LittleEndianReader::LittleEndianReader(const std::filesystem::path& path)
    : path_(path.string()), data_(ReadTextFile(path)) {}

std::string_view LittleEndianReader::ReadBytes(size_t count, const std::string& what) {
  Require(count, what);
  const std::string_view bytes(data_.data() + offset_, count);
  offset_ += count;
  return bytes;
}

std::string LittleEndianReader::ReadNullTerminated(const std::string& what) {
  const size_t end = data_.find('\0', offset_);
  if (end == std::string::npos) {
    Fail("the file ends at byte " + std::to_string(data_.size()) + " inside " + what +
         " (expected a '\\0'-terminated string)");
  }
  std::string text = data_.substr(offset_, end - offset_);
  offset_ = end + 1;
  return text;
}

void LittleEndianReader::RequireCount(uint64_t count, size_t min_bytes, const std::string& what) {
  if (count > remaining() / min_bytes) {
    Fail("truncated or corrupt: " + std::to_string(count) + " " + what + " need at least " +
         std::to_string(count * min_bytes) + " bytes, only " + std::to_string(remaining()) +
         " remain");
  }
}

void LittleEndianReader::ExpectEnd() {
  SetRecord("after the last record");
  if (offset_ != data_.size()) {
    Fail("expected the end of the file, found " + std::to_string(remaining()) + " more bytes");
  }
}

std::string LittleEndianReader::Describe(const std::string& what) const {
  return "at byte offset " + std::to_string(offset_) +
         (record_.empty() ? std::string() : " (" + record_ + ")") + ": " + what;
}

void LittleEndianReader::Fail(const std::string& what) const {
  throw InputError(path_, 0, Describe(what));
}

void LittleEndianReader::Require(size_t num_bytes, const std::string& what) {
  if (remaining() < num_bytes) {
    Fail("truncated file: it ends at byte " + std::to_string(data_.size()) + ", expected " + what +
         " (" + std::to_string(num_bytes) + " bytes)");
  }
}

void LittleEndianWriter::SaveTo(const std::filesystem::path& path) const {
  WriteFileAtomically(
      path,
      [&](std::ostream& stream) {
        stream.write(data_.data(), static_cast<std::streamsize>(data_.size()));
      },
      /*binary=*/true);
}

}  // namespace viosfm

#include "viosfm/io/cdr.h"

#include <cstdio>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

constexpr size_t kEncapsulationBytes = 4;

std::string HexByte(uint8_t byte) {
  char text[3];
  std::snprintf(text, sizeof(text), "%02x", byte);
  return text;
}

}  // namespace

CdrReader::CdrReader(std::span<const uint8_t> bytes, const std::string& where, const char* type)
    : total_size_(bytes.size()), where_(where), type_(type) {
  if (bytes.size() < kEncapsulationBytes) {
    Fail("the message has " + std::to_string(bytes.size()) +
         " bytes, fewer than the 4 of a CDR encapsulation header");
  }
  const uint16_t kind = static_cast<uint16_t>((bytes[0] << 8) | bytes[1]);
  if (kind == 0x0000) {
    big_endian_ = true;
  } else if (kind == 0x0001) {
    big_endian_ = false;
  } else {
    std::string name;
    switch (kind) {
      case 0x0002: name = " (PL_CDR_BE, parameter list)"; break;
      case 0x0003: name = " (PL_CDR_LE, parameter list)"; break;
      case 0x0006: name = " (CDR2_BE, XCDR2)"; break;
      case 0x0007: name = " (CDR2_LE, XCDR2)"; break;
      case 0x0008: name = " (D_CDR2_BE, XCDR2)"; break;
      case 0x0009: name = " (D_CDR2_LE, XCDR2)"; break;
      case 0x000a: name = " (PL_CDR2_BE, XCDR2)"; break;
      case 0x000b: name = " (PL_CDR2_LE, XCDR2)"; break;
      default: break;
    }
    Fail("CDR encapsulation " + HexByte(bytes[0]) + " " + HexByte(bytes[1]) + name +
         " is not read (expected 00 00 or 00 01: plain CDR, big- or little-endian, as ROS 2 "
         "writes; is this a CDR message?)");
  }
  bytes_ = bytes.subspan(kEncapsulationBytes);
}

void CdrReader::Align(size_t size, const char* field) {
  const size_t padding = (size - offset_ % size) % size;
  if (padding == 0) return;
  Require(padding, field);
  offset_ += padding;
}

void CdrReader::Require(uint64_t size, const char* field) {
  if (size > bytes_.size() - offset_) {
    Fail(std::string(field) + " needs " + std::to_string(size) + " bytes at message offset " +
         std::to_string(kEncapsulationBytes + offset_) + ", only " +
         std::to_string(bytes_.size() - offset_) + " left (the message has " +
         std::to_string(total_size_) + " bytes)");
  }
}

std::string CdrReader::GetString(const char* field) {
  const uint32_t length = Get<uint32_t>(field);
  if (length == 0) return "";  // some writers store an empty string without its NUL
  Require(length, field);
  const char* text = reinterpret_cast<const char*>(bytes_.data() + offset_);
  if (text[length - 1] != '\0') {
    Fail(std::string(field) + ": a string of " + std::to_string(length) +
         " bytes without its terminating NUL (not CDR?)");
  }
  offset_ += length;
  return std::string(text, length - 1);
}

std::span<const uint8_t> CdrReader::GetByteSequence(const char* field) {
  const uint32_t length = Get<uint32_t>(field);
  Require(length, field);
  const std::span<const uint8_t> out = bytes_.subspan(offset_, length);
  offset_ += length;
  return out;
}

void CdrReader::ExpectEnd() {
  const size_t left = bytes_.size() - offset_;
  // Nothing, or the up to 3 bytes that pad the message to a multiple of 4.
  if (left == 0 || left == (4 - (kEncapsulationBytes + offset_) % 4) % 4) return;
  Fail(std::to_string(left) + " bytes left after the message (" + std::to_string(total_size_) +
       " bytes in all): not a " + type_ + "?");
}

void CdrReader::Fail(const std::string& what) const {
  throw InputError(where_ + ": " + type_ + ": " + what);
}

CdrWriter::CdrWriter() : bytes_{0x00, 0x01, 0x00, 0x00} {}

void CdrWriter::Align(size_t size) {
  const size_t offset = bytes_.size() - kEncapsulationBytes;
  bytes_.resize(bytes_.size() + (size - offset % size) % size, 0);
}

void CdrWriter::PutString(const std::string& text) {
  VIOSFM_CHECK_LT(text.size(), 0xffffffffu) << "CDR string too long";
  Put<uint32_t>(static_cast<uint32_t>(text.size() + 1));
  bytes_.insert(bytes_.end(), text.begin(), text.end());
  bytes_.push_back(0);
}

void CdrWriter::PutByteSequence(std::span<const uint8_t> data) {
  VIOSFM_CHECK_LE(data.size(), 0xffffffffu) << "CDR sequence too long";
  Put<uint32_t>(static_cast<uint32_t>(data.size()));
  bytes_.insert(bytes_.end(), data.begin(), data.end());
}

std::vector<uint8_t> CdrWriter::Take() {
  bytes_.resize((bytes_.size() + 3) / 4 * 4, 0);
  return std::move(bytes_);
}

}  // namespace viosfm

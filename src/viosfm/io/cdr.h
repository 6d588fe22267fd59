// CDR, the serialization of ROS 2 messages (rmw_fastrtps, rmw_cyclonedds):
// OMG XCDR version 1 ("plain CDR") as DDS-XTypes defines it.
//
//   encapsulation  4 bytes: 00 00 big-endian or 00 01 little-endian, then two
//                  option bytes (ignored)
//   primitives     aligned to their own size (1, 2, 4, 8), counted from the
//                  first byte after the encapsulation; the padding is skipped
//   string         uint32 length counting a terminating NUL, the bytes, NUL
//   sequence T[]   uint32 element count, then the elements
//   array T[N]     the N elements, no count
//   nested struct  its fields inline (no alignment of its own)
//
// A message may end with up to 3 padding bytes that make its length a
// multiple of 4 (most writers add them, some do not).
//
// CdrReader throws InputError("<where>: <type>: <what>") on every overrun,
// unknown encapsulation or malformed string; CdrWriter writes little-endian
// XCDR1 padded to a multiple of 4, as ROS 2 does.
#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace viosfm {

class CdrReader {
 public:
  // Reads the encapsulation header; `where` and `type` prefix error messages.
  CdrReader(std::span<const uint8_t> bytes, const std::string& where, const char* type);

  bool big_endian() const { return big_endian_; }

  template <typename T>
  T Get(const char* field) {
    static_assert(std::is_arithmetic_v<T>);
    Align(sizeof(T), field);
    Require(sizeof(T), field);
    uint64_t bits = 0;
    for (size_t i = 0; i < sizeof(T); ++i) {
      const uint64_t byte = bytes_[offset_ + i];
      bits |= byte << (8 * (big_endian_ ? sizeof(T) - 1 - i : i));
    }
    offset_ += sizeof(T);
    if constexpr (std::is_same_v<T, double>) {
      return std::bit_cast<double>(bits);
    } else if constexpr (std::is_same_v<T, float>) {
      return std::bit_cast<float>(static_cast<uint32_t>(bits));
    } else {
      return static_cast<T>(bits);
    }
  }
  std::string GetString(const char* field);
  // A uint8[] sequence: its bytes, valid while the message's bytes are.
  std::span<const uint8_t> GetByteSequence(const char* field);
  // Throws unless the message ends here (padding to a multiple of 4 allowed).
  void ExpectEnd();
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  void Align(size_t size, const char* field);
  void Require(uint64_t size, const char* field);

  std::span<const uint8_t> bytes_;  // after the encapsulation header
  size_t offset_ = 0;
  size_t total_size_ = 0;
  bool big_endian_ = false;
  const std::string& where_;
  const char* type_;
};

class CdrWriter {
 public:
  CdrWriter();

  template <typename T>
  void Put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    Align(sizeof(T));
    uint64_t bits = 0;
    if constexpr (std::is_same_v<T, double>) {
      bits = std::bit_cast<uint64_t>(value);
    } else if constexpr (std::is_same_v<T, float>) {
      bits = std::bit_cast<uint32_t>(value);
    } else {
      bits = static_cast<uint64_t>(static_cast<std::make_unsigned_t<T>>(value));
    }
    for (size_t i = 0; i < sizeof(T); ++i) bytes_.push_back(static_cast<uint8_t>(bits >> (8 * i)));
  }
  void PutString(const std::string& text);
  void PutByteSequence(std::span<const uint8_t> data);
  // The message, padded to a multiple of 4 bytes.
  std::vector<uint8_t> Take();

 private:
  void Align(size_t size);
  std::vector<uint8_t> bytes_;  // starting with the encapsulation header
};

}  // namespace viosfm

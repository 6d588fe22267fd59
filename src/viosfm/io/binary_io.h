// Little-endian binary files (COLMAP's .bin models, viosfm's vocabulary
// files): a sequential reader whose every failure throws InputError naming
// the file, the byte offset, the record being read and what was expected,
// and a writer that saves atomically.
#pragma once

#include <bit>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>

namespace viosfm {

class LittleEndianReader {
 public:
  // Reads the whole file (InputError if it cannot be read).
  explicit LittleEndianReader(const std::filesystem::path& path);

  // Describes the record being read, for error messages ("camera record 2 of 5").
  void SetRecord(std::string record) { record_ = std::move(record); }

  // An integer, float or double; `what` names it in errors.
  template <typename T>
  T Read(const std::string& what) {
    static_assert(std::is_integral_v<T> || std::is_floating_point_v<T>);
    Require(sizeof(T), what);
    uint64_t bits = 0;
    for (size_t i = 0; i < sizeof(T); ++i) {
      bits |= static_cast<uint64_t>(static_cast<uint8_t>(data_[offset_ + i])) << (8 * i);
    }
    offset_ += sizeof(T);
    if constexpr (std::is_same_v<T, double>) {
      return std::bit_cast<double>(bits);
    } else if constexpr (std::is_same_v<T, float>) {
      return std::bit_cast<float>(static_cast<uint32_t>(bits));
    } else {
      return static_cast<T>(static_cast<std::make_unsigned_t<T>>(bits));
    }
  }
  std::string_view ReadBytes(size_t count, const std::string& what);
  std::string ReadNullTerminated(const std::string& what);

  // Checks that `count` records of at least `min_bytes` each can follow
  // (guards allocations against corrupt counts).
  void RequireCount(uint64_t count, size_t min_bytes, const std::string& what);
  void ExpectEnd();

  size_t offset() const { return offset_; }
  size_t remaining() const { return data_.size() - offset_; }
  const std::string& path() const { return path_; }

  // "at byte offset N (record): what", the message Fail throws.
  std::string Describe(const std::string& what) const;
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  void Require(size_t num_bytes, const std::string& what);

  std::string path_;
  std::string data_;
  size_t offset_ = 0;
  std::string record_;
};

class LittleEndianWriter {
 public:
  template <typename T>
  void Write(T value) {
    static_assert(std::is_integral_v<T> || std::is_floating_point_v<T>);
    uint64_t bits = 0;
    if constexpr (std::is_same_v<T, double>) {
      bits = std::bit_cast<uint64_t>(value);
    } else if constexpr (std::is_same_v<T, float>) {
      bits = std::bit_cast<uint32_t>(value);
    } else {
      bits = static_cast<std::make_unsigned_t<T>>(value);
    }
    for (size_t i = 0; i < sizeof(T); ++i)
      data_.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
  }
  void WriteBytes(std::string_view bytes) { data_ += bytes; }
  void WriteNullTerminated(const std::string& text) {
    data_ += text;
    data_.push_back('\0');
  }
  void Reserve(size_t bytes) { data_.reserve(bytes); }
  // Writes everything to `path` atomically (temporary file, then rename).
  void SaveTo(const std::filesystem::path& path) const;

 private:
  std::string data_;
};

}  // namespace viosfm

// The little-endian integers and the positioned reads of the bag files'
// readers and writers (rosbag.h: ROS 1 bags, mcap.h: MCAP files).
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

#include "viosfm/util/errors.h"

namespace viosfm {

inline uint32_t LoadU32(const uint8_t* bytes) {
  return uint32_t{bytes[0]} | (uint32_t{bytes[1]} << 8) | (uint32_t{bytes[2]} << 16) |
         (uint32_t{bytes[3]} << 24);
}
inline uint64_t LoadU64(const uint8_t* bytes) {
  return uint64_t{LoadU32(bytes)} | (uint64_t{LoadU32(bytes + 4)} << 32);
}

inline void AppendU32(std::string& out, uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}
inline void AppendU64(std::string& out, uint64_t value) {
  AppendU32(out, static_cast<uint32_t>(value & 0xffffffffu));
  AppendU32(out, static_cast<uint32_t>(value >> 32));
}

// "byte offset N", where an error message places a record.
inline std::string ByteOffset(uint64_t offset) {
  return "byte offset " + std::to_string(offset);
}

// Reads exactly `size` bytes at `offset` of `file` (of `file_size` bytes);
// InputError naming `path`, the offset and `what` when the file ends first
// ("... (the <container> is truncated)") or cannot be read.
inline void ReadAt(std::ifstream& file, const std::string& path, uint64_t file_size,
                   uint64_t offset, uint8_t* out, uint64_t size, const std::string& what,
                   const char* container) {
  if (offset > file_size || size > file_size - offset) {
    throw InputError(path, 0,
                     ByteOffset(offset) + ": " + what + ": expected " + std::to_string(size) +
                         " bytes, the file ends after " +
                         std::to_string(offset > file_size ? 0 : file_size - offset) + " (the " +
                         container + " is truncated)");
  }
  file.clear();
  file.seekg(static_cast<std::streamoff>(offset));
  file.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(size));
  if (!file) throw InputError(path, 0, ByteOffset(offset) + ": " + what + ": read error");
}

}  // namespace viosfm

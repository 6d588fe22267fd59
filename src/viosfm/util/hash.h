// Content hashes, for telling apart inputs that differ by accident (another
// dataset, an edited calibration or image, a trajectory file written again),
// as the run fingerprint does (pipeline/run_fingerprint.h): 64-bit FNV-1a
// (Fowler, Noll, Vo) for the short records a program builds (field by
// field), XXH3 (xxHash) for files. Neither is cryptographic: inputs made to
// collide on purpose are not detected; two different inputs of a run share
// a hash with probability about 2^-64.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>

namespace viosfm {

class Fnv1a64 {
 public:
  static constexpr uint64_t kOffsetBasis = 0xcbf29ce484222325ULL;
  static constexpr uint64_t kPrime = 0x100000001b3ULL;

  void Update(const void* data, size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    uint64_t hash = hash_;
    for (size_t i = 0; i < size; ++i) {
      hash ^= bytes[i];
      hash *= kPrime;
    }
    hash_ = hash;
  }
  void Update(std::string_view text) { Update(text.data(), text.size()); }
  // A string followed by its length, so that ("ab", "c") and ("a", "bc")
  // hash differently.
  void UpdateField(std::string_view text) {
    Update(text);
    UpdateValue(static_cast<uint64_t>(text.size()));
  }
  // The value's bytes as they are in memory (little-endian on every machine
  // viosfm builds on); doubles bit for bit (so -0.0 differs from 0.0).
  template <typename T>
  void UpdateValue(const T& value) {
    static_assert(std::is_arithmetic_v<T>, "UpdateValue takes numbers");
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    Update(bytes, sizeof(T));
  }

  uint64_t digest() const { return hash_; }
  // 16 lower-case hex digits.
  std::string HexDigest() const;

 private:
  uint64_t hash_ = kOffsetBasis;
};

uint64_t Fnv1a64Hash(std::string_view text);
// 16 lower-case hex digits of `hash`.
std::string HashToHex(uint64_t hash);

// XXH3 (64 bits, xxHash: libxxhash) of `size` bytes: a fast,
// non-cryptographic content hash (about 10 GB/s, so hashing a file costs
// little more than reading it).
uint64_t Xxh3Hash(const void* data, size_t size);

// The size and XXH3 hash of a file's whole content (an input of a run, an
// image), read in 1 MiB blocks.
struct FileHash {
  uintmax_t size = 0;  // bytes
  uint64_t hash = 0;
  // "1234 bytes, xxh3 0123456789abcdef"
  std::string ToString() const;
};
// Throws InputError naming the file if it cannot be opened or read.
FileHash HashFile(const std::filesystem::path& path);

}  // namespace viosfm

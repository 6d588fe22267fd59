#include "viosfm/util/hash.h"

#include <xxhash.h>

#include <fstream>
#include <memory>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {

std::string HashToHex(uint64_t hash) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text(16, '0');
  for (int i = 15; i >= 0; --i) {
    text[i] = kDigits[hash & 0xf];
    hash >>= 4;
  }
  return text;
}

std::string Fnv1a64::HexDigest() const {
  return HashToHex(hash_);
}

uint64_t Fnv1a64Hash(std::string_view text) {
  Fnv1a64 hash;
  hash.Update(text);
  return hash.digest();
}

std::string FileHash::ToString() const {
  return std::to_string(size) + " bytes, xxh3 " + HashToHex(hash);
}

uint64_t Xxh3Hash(const void* data, size_t size) {
  return XXH3_64bits(data, size);
}

FileHash HashFile(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw InputError(path.string(), 0, "cannot open for reading");
  std::unique_ptr<XXH3_state_t, decltype(&XXH3_freeState)> state(XXH3_createState(),
                                                                 &XXH3_freeState);
  VIOSFM_CHECK(state != nullptr && XXH3_64bits_reset(state.get()) == XXH_OK);
  FileHash result;
  std::vector<char> block(1 << 20);
  while (stream) {
    stream.read(block.data(), static_cast<std::streamsize>(block.size()));
    const std::streamsize count = stream.gcount();
    if (count <= 0) break;
    VIOSFM_CHECK(XXH3_64bits_update(state.get(), block.data(), static_cast<size_t>(count)) ==
                 XXH_OK);
    result.size += static_cast<uintmax_t>(count);
  }
  if (stream.bad()) throw InputError(path.string(), 0, "read failed");
  result.hash = XXH3_64bits_digest(state.get());
  return result;
}

}  // namespace viosfm

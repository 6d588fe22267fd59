#include "viosfm/util/hash.h"

#include <fstream>
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
  return std::to_string(size) + " bytes, fnv1a64 " + HashToHex(hash);
}

FileHash HashFile(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw InputError(path.string(), 0, "cannot open for reading");
  Fnv1a64 hash;
  FileHash result;
  std::vector<char> block(1 << 20);
  while (stream) {
    stream.read(block.data(), static_cast<std::streamsize>(block.size()));
    const std::streamsize count = stream.gcount();
    if (count <= 0) break;
    hash.Update(block.data(), static_cast<size_t>(count));
    result.size += static_cast<uintmax_t>(count);
  }
  if (stream.bad()) throw InputError(path.string(), 0, "read failed");
  result.hash = hash.digest();
  return result;
}

}  // namespace viosfm

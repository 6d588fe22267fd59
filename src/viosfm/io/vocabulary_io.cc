#include "viosfm/io/vocabulary_io.h"

#include <bit>
#include <cstring>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace fs = std::filesystem;
namespace {

constexpr std::string_view kMagic = "VIOSFMVT";
// Bytes per node record (three int32).
constexpr uint64_t kNodeRecordBytes = 12;

// Appends the little-endian bytes of an integer or float.
template <typename T>
void Append(T value, std::string* out) {
  static_assert(std::is_integral_v<T> || std::is_same_v<T, float>);
  uint64_t bits = 0;
  if constexpr (std::is_same_v<T, float>) {
    bits = std::bit_cast<uint32_t>(value);
  } else {
    bits = static_cast<std::make_unsigned_t<T>>(value);
  }
  for (size_t i = 0; i < sizeof(T); ++i)
    out->push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
}

// Sequential little-endian reader over a whole file; every failure throws
// InputError naming the file, the byte offset and what was expected.
class Reader {
 public:
  Reader(std::string path, std::string data) : path_(std::move(path)), data_(std::move(data)) {}

  template <typename T>
  T Read(const std::string& what) {
    Require(sizeof(T), what);
    uint64_t bits = 0;
    for (size_t i = 0; i < sizeof(T); ++i) {
      bits |= static_cast<uint64_t>(static_cast<uint8_t>(data_[offset_ + i])) << (8 * i);
    }
    offset_ += sizeof(T);
    if constexpr (std::is_same_v<T, float>) {
      return std::bit_cast<float>(static_cast<uint32_t>(bits));
    } else {
      return static_cast<T>(static_cast<std::make_unsigned_t<T>>(bits));
    }
  }

  std::string_view ReadBytes(size_t count, const std::string& what) {
    Require(count, what);
    const std::string_view bytes(data_.data() + offset_, count);
    offset_ += count;
    return bytes;
  }

  size_t remaining() const { return data_.size() - offset_; }

  void ExpectEnd() {
    if (offset_ != data_.size()) {
      Fail("expected the end of the file, found " + std::to_string(remaining()) + " more bytes");
    }
  }

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_, 0, "at byte offset " + std::to_string(offset_) + ": " + what);
  }

 private:
  void Require(size_t num_bytes, const std::string& what) {
    if (remaining() < num_bytes) {
      Fail("truncated file: it ends at byte " + std::to_string(data_.size()) + ", expected " +
           what + " (" + std::to_string(num_bytes) + " bytes)");
    }
  }

  std::string path_;
  std::string data_;
  size_t offset_ = 0;
};

}  // namespace

void WriteVocabulary(const fs::path& path, const VocabularyData& vocabulary) {
  const std::string problem = vocabulary.Validate();
  VIOSFM_CHECK(problem.empty()) << "writing an inconsistent vocabulary to " << path.string() << ": "
                                << problem;
  const uint64_t num_nodes = static_cast<uint64_t>(vocabulary.num_nodes());
  std::string bytes;
  bytes.reserve(kMagic.size() + 28 + num_nodes * kNodeRecordBytes + vocabulary.centers.size() * 4);
  bytes.append(kMagic);
  Append<uint32_t>(kVocabularyFileVersion, &bytes);
  Append<int32_t>(vocabulary.branching, &bytes);
  Append<int32_t>(vocabulary.depth, &bytes);
  Append<int32_t>(vocabulary.descriptor_dim, &bytes);
  Append<int32_t>(vocabulary.num_words, &bytes);
  Append<uint64_t>(num_nodes, &bytes);
  for (uint64_t node = 0; node < num_nodes; ++node) {
    Append<int32_t>(vocabulary.first_child[node], &bytes);
    Append<int32_t>(vocabulary.num_children[node], &bytes);
    Append<int32_t>(vocabulary.word_of_node[node], &bytes);
  }
  for (const float value : vocabulary.centers) Append<float>(value, &bytes);
  WriteFileAtomically(
      path, [&bytes](std::ostream& stream) { stream.write(bytes.data(), bytes.size()); },
      /*binary=*/true);
}

VocabularyData ReadVocabulary(const fs::path& path) {
  Reader reader(path.string(), ReadTextFile(path));
  const std::string_view magic = reader.ReadBytes(kMagic.size(), "the magic \"VIOSFMVT\"");
  if (magic != kMagic) {
    reader.Fail("bad magic: not a viosfm vocabulary file (expected it to start with \"VIOSFMVT\")");
  }
  const uint32_t version = reader.Read<uint32_t>("the format version (uint32)");
  if (version != kVocabularyFileVersion) {
    reader.Fail("unsupported vocabulary format version " + std::to_string(version) + ", expected " +
                std::to_string(kVocabularyFileVersion));
  }
  VocabularyData vocabulary;
  vocabulary.branching = reader.Read<int32_t>("the branching factor (int32)");
  vocabulary.depth = reader.Read<int32_t>("the depth (int32)");
  vocabulary.descriptor_dim = reader.Read<int32_t>("the descriptor dimension (int32)");
  vocabulary.num_words = reader.Read<int32_t>("the number of words (int32)");
  const uint64_t num_nodes = reader.Read<uint64_t>("the number of nodes (uint64)");
  if (vocabulary.descriptor_dim < 1 || vocabulary.descriptor_dim > 4096) {
    reader.Fail("descriptor dimension " + std::to_string(vocabulary.descriptor_dim) +
                " outside [1, 4096]");
  }
  const uint64_t node_bytes =
      kNodeRecordBytes + 4 * static_cast<uint64_t>(vocabulary.descriptor_dim);
  if (num_nodes == 0 || num_nodes > reader.remaining() / node_bytes) {
    reader.Fail("truncated or corrupt: " + std::to_string(num_nodes) + " nodes need " +
                std::to_string(num_nodes) + " x " + std::to_string(node_bytes) + " bytes, " +
                std::to_string(reader.remaining()) + " remain");
  }
  vocabulary.first_child.resize(num_nodes);
  vocabulary.num_children.resize(num_nodes);
  vocabulary.word_of_node.resize(num_nodes);
  for (uint64_t node = 0; node < num_nodes; ++node) {
    vocabulary.first_child[node] = reader.Read<int32_t>("first_child (int32)");
    vocabulary.num_children[node] = reader.Read<int32_t>("num_children (int32)");
    vocabulary.word_of_node[node] = reader.Read<int32_t>("word_of_node (int32)");
  }
  vocabulary.centers.resize(num_nodes * vocabulary.descriptor_dim);
  for (float& value : vocabulary.centers) value = reader.Read<float>("a centre value (float32)");
  reader.ExpectEnd();
  const std::string problem = vocabulary.Validate();
  if (!problem.empty())
    throw InputError(path.string(), 0, "inconsistent vocabulary tree: " + problem);
  return vocabulary;
}

}  // namespace viosfm

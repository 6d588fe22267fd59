#include "viosfm/io/vocabulary_io.h"

#include <bit>
#include <cstring>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>

#include "viosfm/io/binary_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace fs = std::filesystem;
namespace {

constexpr std::string_view kMagic = "VIOSFMVT";
// Bytes per node record (three int32).
constexpr uint64_t kNodeRecordBytes = 12;

}  // namespace

void WriteVocabulary(const fs::path& path, const VocabularyData& vocabulary) {
  const std::string problem = vocabulary.Validate();
  VIOSFM_CHECK(problem.empty()) << "writing an inconsistent vocabulary to " << path.string() << ": "
                                << problem;
  const uint64_t num_nodes = static_cast<uint64_t>(vocabulary.num_nodes());
  LittleEndianWriter bytes;
  bytes.Reserve(kMagic.size() + 28 + num_nodes * kNodeRecordBytes + vocabulary.centers.size() * 4);
  bytes.WriteBytes(kMagic);
  bytes.Write<uint32_t>(kVocabularyFileVersion);
  bytes.Write<int32_t>(vocabulary.branching);
  bytes.Write<int32_t>(vocabulary.depth);
  bytes.Write<int32_t>(vocabulary.descriptor_dim);
  bytes.Write<int32_t>(vocabulary.num_words);
  bytes.Write<uint64_t>(num_nodes);
  for (uint64_t node = 0; node < num_nodes; ++node) {
    bytes.Write<int32_t>(vocabulary.first_child[node]);
    bytes.Write<int32_t>(vocabulary.num_children[node]);
    bytes.Write<int32_t>(vocabulary.word_of_node[node]);
  }
  for (const float value : vocabulary.centers) bytes.Write<float>(value);
  bytes.SaveTo(path);
}

VocabularyData ReadVocabulary(const fs::path& path) {
  LittleEndianReader reader(path);
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

// Binary vocabulary-tree files (scene/vocabulary_data.h).
//
// Layout, all integers and floats little-endian:
//   char[8]  magic "VIOSFMVT"
//   uint32   format version (kVocabularyFileVersion)
//   int32    branching, depth, descriptor_dim, num_words
//   uint64   num_nodes
//   num_nodes x { int32 first_child, int32 num_children, int32 word_of_node }
//   num_nodes x descriptor_dim float32 centres
// and nothing after. Files are written atomically (temporary + rename).
#pragma once

#include <cstdint>
#include <filesystem>

#include "viosfm/scene/vocabulary_data.h"

namespace viosfm {

inline constexpr uint32_t kVocabularyFileVersion = 1;

// Throws InternalError if `vocabulary` is inconsistent, InputError on I/O failure.
void WriteVocabulary(const std::filesystem::path& path, const VocabularyData& vocabulary);

// Throws InputError naming the file and what is wrong: missing, bad magic,
// unsupported version, truncated, trailing bytes, inconsistent tree.
VocabularyData ReadVocabulary(const std::filesystem::path& path);

}  // namespace viosfm

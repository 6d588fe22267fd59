#include "viosfm/io/vocabulary_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// Root with two children; the first child has two leaf children, the second is a leaf.
VocabularyData SmallTree() {
  VocabularyData data;
  data.branching = 2;
  data.depth = 2;
  data.descriptor_dim = 3;
  data.num_words = 3;
  data.first_child = {1, 3, -1, -1, -1};
  data.num_children = {2, 2, 0, 0, 0};
  data.word_of_node = {-1, -1, 2, 0, 1};
  data.centers = {0, 0, 0, 1.5f, -2, 3, 4, 5, 6, 0.25f, 1e-7f, -1e30f, 7, 8, 9};
  return data;
}

std::string ReadBytes(const std::filesystem::path& path) {
  return ReadTextFile(path);
}

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), bytes.size());
}

// Runs ReadVocabulary and returns the InputError message ("" if none).
std::string ReadError(const std::filesystem::path& path) {
  try {
    ReadVocabulary(path);
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(VocabularyIo, SmallTreeIsValid) {
  EXPECT_EQ(SmallTree().Validate(), "");
}

TEST(VocabularyIo, RoundTripIsExactAndByteIdentical) {
  const auto folder = testing::MakeScratchFolder("vocabulary_round_trip");
  const VocabularyData data = SmallTree();
  WriteVocabulary(folder / "a.bin", data);
  const VocabularyData read = ReadVocabulary(folder / "a.bin");
  EXPECT_EQ(read.branching, data.branching);
  EXPECT_EQ(read.depth, data.depth);
  EXPECT_EQ(read.descriptor_dim, data.descriptor_dim);
  EXPECT_EQ(read.num_words, data.num_words);
  EXPECT_EQ(read.first_child, data.first_child);
  EXPECT_EQ(read.num_children, data.num_children);
  EXPECT_EQ(read.word_of_node, data.word_of_node);
  EXPECT_EQ(read.centers, data.centers);  // bit-exact floats
  WriteVocabulary(folder / "b.bin", read);
  const std::string bytes = ReadBytes(folder / "a.bin");
  EXPECT_EQ(bytes, ReadBytes(folder / "b.bin"));
  // Header 8 + 4 + 4 * 4 + 8 bytes, 5 nodes of 12 bytes, 15 floats.
  EXPECT_EQ(bytes.size(), 36u + 5 * 12 + 15 * 4);
  EXPECT_EQ(bytes.substr(0, 8), "VIOSFMVT");
  // No temporary file left behind.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(folder),
                          std::filesystem::directory_iterator{}),
            2);
}

TEST(VocabularyIo, RejectsMissingFile) {
  const auto folder = testing::MakeScratchFolder("vocabulary_missing");
  EXPECT_THAT(ReadError(folder / "none.bin"),
              AllOf(HasSubstr("none.bin"), HasSubstr("does not exist")));
}

TEST(VocabularyIo, RejectsBadMagic) {
  const auto folder = testing::MakeScratchFolder("vocabulary_magic");
  WriteVocabulary(folder / "v.bin", SmallTree());
  std::string bytes = ReadBytes(folder / "v.bin");
  bytes[0] = 'X';
  WriteBytes(folder / "v.bin", bytes);
  EXPECT_THAT(ReadError(folder / "v.bin"), AllOf(HasSubstr("v.bin"), HasSubstr("bad magic")));
  WriteBytes(folder / "v.bin", "VIO");
  EXPECT_THAT(ReadError(folder / "v.bin"), AllOf(HasSubstr("v.bin"), HasSubstr("truncated")));
}

TEST(VocabularyIo, RejectsOtherVersion) {
  const auto folder = testing::MakeScratchFolder("vocabulary_version");
  WriteVocabulary(folder / "v.bin", SmallTree());
  std::string bytes = ReadBytes(folder / "v.bin");
  bytes[8] = 7;  // version, little-endian
  WriteBytes(folder / "v.bin", bytes);
  EXPECT_THAT(ReadError(folder / "v.bin"),
              AllOf(HasSubstr("v.bin"), HasSubstr("version 7"), HasSubstr("expected 1")));
}

TEST(VocabularyIo, RejectsEveryTruncation) {
  const auto folder = testing::MakeScratchFolder("vocabulary_truncated");
  WriteVocabulary(folder / "v.bin", SmallTree());
  const std::string bytes = ReadBytes(folder / "v.bin");
  for (size_t size = 0; size < bytes.size(); ++size) {
    WriteBytes(folder / "t.bin", bytes.substr(0, size));
    const std::string message = ReadError(folder / "t.bin");
    EXPECT_THAT(message, AllOf(HasSubstr("t.bin"), HasSubstr("truncated"))) << "size " << size;
  }
}

TEST(VocabularyIo, RejectsTrailingBytes) {
  const auto folder = testing::MakeScratchFolder("vocabulary_trailing");
  WriteVocabulary(folder / "v.bin", SmallTree());
  WriteBytes(folder / "v.bin", ReadBytes(folder / "v.bin") + "xyz");
  EXPECT_THAT(ReadError(folder / "v.bin"), HasSubstr("expected the end of the file, found 3"));
}

TEST(VocabularyIo, RejectsInconsistentTree) {
  const auto folder = testing::MakeScratchFolder("vocabulary_inconsistent");
  WriteVocabulary(folder / "v.bin", SmallTree());
  std::string bytes = ReadBytes(folder / "v.bin");
  // word_of_node of node 3 (offset 36 + 3 * 12 + 8) := 2, a word used twice.
  bytes[36 + 3 * 12 + 8] = 2;
  WriteBytes(folder / "v.bin", bytes);
  EXPECT_THAT(ReadError(folder / "v.bin"),
              AllOf(HasSubstr("v.bin"), HasSubstr("inconsistent"), HasSubstr("used twice")));
}

TEST(VocabularyData, ValidateNamesProblems) {
  VocabularyData data = SmallTree();
  data.first_child[1] = 0;
  EXPECT_THAT(data.Validate(), HasSubstr("node 1"));
  data = SmallTree();
  data.centers.pop_back();
  EXPECT_THAT(data.Validate(), HasSubstr("centers"));
  data = SmallTree();
  data.num_words = 4;
  EXPECT_THAT(data.Validate(), HasSubstr("3 leaves"));
  data.num_words = 2000000000;  // from a corrupt file: rejected before any allocation
  EXPECT_THAT(data.Validate(), HasSubstr("num_words 2000000000 outside [1, num_nodes = 5]"));
  EXPECT_THROW(WriteVocabulary(testing::MakeScratchFolder("vocabulary_bad") / "v.bin", data),
               InternalError);
}

}  // namespace
}  // namespace viosfm

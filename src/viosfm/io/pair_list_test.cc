#include "viosfm/io/pair_list.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

TEST(PairList, RoundTripIsByteIdentical) {
  const fs::path dir = testing::MakeScratchFolder("pair_list_round_trip");
  const std::vector<ImageNamePair> pairs = {
      {"cam0/1403715273262142976.png", "cam0/1403715273312143104.png"},
      {"b.png", "a.png"},
      {"dir/x.jpg", "dir/y.jpg"}};
  const fs::path path = dir / "pairs.txt";
  WriteImagePairList(path, pairs);
  EXPECT_EQ(ReadTextFile(path),
            "cam0/1403715273262142976.png cam0/1403715273312143104.png\n"
            "b.png a.png\n"
            "dir/x.jpg dir/y.jpg\n");
  const ImageNamePairList read = ReadImagePairList(path);
  EXPECT_EQ(read.path, path);
  ASSERT_EQ(read.pairs.size(), 3u);
  for (size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(read.pairs[i].name1, pairs[i].name1);
    EXPECT_EQ(read.pairs[i].name2, pairs[i].name2);
    EXPECT_EQ(read.pairs[i].line, static_cast<int64_t>(i + 1));
  }
  const fs::path again = dir / "again.txt";
  WriteImagePairList(again, read.pairs);
  EXPECT_EQ(ReadTextFile(again), ReadTextFile(path));
}

TEST(PairList, SkipsCommentsAndBlankLinesAndAcceptsTabsAndCrlf) {
  const fs::path dir = testing::MakeScratchFolder("pair_list_comments");
  const fs::path path = dir / "pairs.txt";
  WriteText(path, "# comment\n\n  a.png\tb.png  \r\n#c d\nc.png   d.png\n");
  const ImageNamePairList read = ReadImagePairList(path);
  ASSERT_EQ(read.pairs.size(), 2u);
  EXPECT_EQ(read.pairs[0].name1, "a.png");
  EXPECT_EQ(read.pairs[0].name2, "b.png");
  EXPECT_EQ(read.pairs[0].line, 3);
  EXPECT_EQ(read.pairs[1].name1, "c.png");
  EXPECT_EQ(read.pairs[1].name2, "d.png");
  EXPECT_EQ(read.pairs[1].line, 5);
}

std::string ReadError(const fs::path& path) {
  try {
    ReadImagePairList(path);
  } catch (const InputError& error) {
    return error.what();
  }
  return "no error";
}

TEST(PairList, ErrorsNameFileAndLine) {
  const fs::path dir = testing::MakeScratchFolder("pair_list_errors");
  const fs::path three = dir / "three.txt";
  WriteText(three, "a b\n\na b c\n");
  EXPECT_THAT(ReadError(three), HasSubstr(three.string() + ":3:"));
  EXPECT_THAT(ReadError(three), HasSubstr("expected two image names"));

  const fs::path one = dir / "one.txt";
  WriteText(one, "# x\nonly_one\n");
  EXPECT_THAT(ReadError(one), HasSubstr(one.string() + ":2:"));
  EXPECT_THAT(ReadError(one), HasSubstr("got 1 field(s)"));

  const fs::path same = dir / "same.txt";
  WriteText(same, "a.png a.png\n");
  EXPECT_THAT(ReadError(same), HasSubstr(same.string() + ":1:"));
  EXPECT_THAT(ReadError(same), HasSubstr("two different images"));

  EXPECT_THAT(ReadError(dir / "missing.txt"), HasSubstr("missing.txt"));
}

TEST(PairList, RefusesNamesTheFormatCannotHold) {
  const fs::path dir = testing::MakeScratchFolder("pair_list_bad_names");
  const fs::path path = dir / "pairs.txt";
  EXPECT_THROW(WriteImagePairList(path, {{"with space.png", "b.png"}}), InputError);
  EXPECT_THROW(WriteImagePairList(path, {{"", "b.png"}}), InputError);
  EXPECT_THROW(WriteImagePairList(path, {{"a.png", "#b.png"}}), InputError);
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace viosfm

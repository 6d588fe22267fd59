#include "viosfm/io/text_lines.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::vector<std::pair<int64_t, std::string>> Lines(const fs::path& path) {
  std::vector<std::pair<int64_t, std::string>> lines;
  ForEachDataLine(path, "test file",
                  [&](int64_t line, std::string_view text) { lines.emplace_back(line, text); });
  return lines;
}

TEST(ForEachDataLine, DataLinesWithTheirNumbers) {
  const fs::path folder = testing::MakeScratchFolder("text_lines");
  testing::WriteTextFile(folder / "a.csv", "# header\n\n1,2\r\n  # indented comment\n 3,4 \n5,6");
  EXPECT_EQ(Lines(folder / "a.csv"),
            (std::vector<std::pair<int64_t, std::string>>{{3, "1,2"}, {5, "3,4"}, {6, "5,6"}}));
  testing::WriteTextFile(folder / "b.csv", "1\n2\n");
  EXPECT_EQ(Lines(folder / "b.csv").size(), 2u);
  testing::WriteTextFile(folder / "empty.csv", "");
  EXPECT_TRUE(Lines(folder / "empty.csv").empty());
}

TEST(ForEachDataLine, ALineLongerThanTheBoundIsAnErrorNamingIt) {
  const fs::path folder = testing::MakeScratchFolder("text_lines_long");
  // A line of exactly the bound is read; one byte more is refused, with its
  // line number, before the rest of the file is read.
  const std::string longest(kMaxTextLineBytes, 'x');
  testing::WriteTextFile(folder / "ok.csv", "1\n" + longest + "\n2\n");
  const auto lines = Lines(folder / "ok.csv");
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[1].second.size(), kMaxTextLineBytes);
  testing::WriteTextFile(folder / "long.csv", "1\n2\n" + longest + "x\n3\n");
  const InputError error = testing::ExpectInputError([&] { Lines(folder / "long.csv"); });
  EXPECT_EQ(error.line(), 3);
  EXPECT_THAT(error.what(), HasSubstr("line longer than 1048576 bytes: not a line of a test file"));
  // Without a newline at all.
  testing::WriteTextFile(folder / "one.csv", longest + longest);
  EXPECT_EQ(testing::ExpectInputError([&] { Lines(folder / "one.csv"); }).line(), 1);
}

}  // namespace
}  // namespace viosfm

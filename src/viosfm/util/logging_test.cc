#include "viosfm/util/logging.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The console's level, restored at the end of a test.
class LogLevelGuard {
 public:
  explicit LogLevelGuard(LogLevel level) : saved_(GetLogLevel()) { SetLogLevel(level); }
  ~LogLevelGuard() { SetLogLevel(saved_); }

 private:
  LogLevel saved_;
};

TEST(LogFile, TakesEveryLevelTheDetailsAndTheConsolesEarlierLines) {
  const fs::path path = testing::MakeScratchFolder("log_file") / "run.log";
  const LogLevelGuard level(LogLevel::kINFO);
  ::testing::internal::CaptureStderr();
  VIOSFM_LOG(INFO) << "before the file opened";
  VIOSFM_LOG(DEBUG) << "a debug line before it: neither on the console nor kept";
  {
    LogFile file(path);
    VIOSFM_LOG(INFO) << "vio: offset kept" << LogDetails() << "; residual 0.03 px over 135 pairs";
    VIOSFM_LOG(DEBUG) << "tracker: 120 corners";
    WriteToLogFile("== a heading");
    LogToFileOnly(LogLevel::kINFO, "a progress bar's last state");
    // Written line by line: a killed process leaves its log up to here.
    const std::vector<std::string> lines = Lines(ReadTextFile(path));
    ASSERT_EQ(lines.size(), 5u);
  }
  VIOSFM_LOG(INFO) << "after the file closed";
  const std::string console = ::testing::internal::GetCapturedStderr();

  const std::vector<std::string> lines = Lines(ReadTextFile(path));
  ASSERT_EQ(lines.size(), 5u);
  // "I YYYY-MM-DD HH:MM:SS.mmm text"
  EXPECT_EQ(lines[0].substr(0, 2), "I ");
  EXPECT_EQ(lines[0].substr(25), " before the file opened");
  EXPECT_EQ(lines[1].substr(25), " vio: offset kept; residual 0.03 px over 135 pairs");
  EXPECT_EQ(lines[2].substr(0, 2), "D ");
  EXPECT_EQ(lines[2].substr(25), " tracker: 120 corners");
  EXPECT_EQ(lines[3], "== a heading");
  EXPECT_EQ(lines[4].substr(25), " a progress bar's last state");

  const std::vector<std::string> shown = Lines(console);
  ASSERT_EQ(shown.size(), 3u);
  EXPECT_EQ(shown[0].substr(10), " before the file opened");
  EXPECT_EQ(shown[1].substr(10), " vio: offset kept");
  EXPECT_EQ(shown[2].substr(10), " after the file closed");
}

TEST(LogFile, AppendsToAnEarlierLog) {
  const fs::path path = testing::MakeScratchFolder("log_file_append") / "run.log";
  testing::WriteTextFile(path, "the earlier run's line\n");
  {
    LogFile file(path);
    WriteToLogFile("the second run's line");
  }
  // Between the two: the console's lines since the last log file closed.
  const std::vector<std::string> lines = Lines(ReadTextFile(path));
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines.front(), "the earlier run's line");
  EXPECT_EQ(lines.back(), "the second run's line");
}

TEST(LogFile, TwoOpenAtOnceBothTakeEveryMessage) {
  const fs::path folder = testing::MakeScratchFolder("log_file_twice");
  {
    LogFile a(folder / "a.log", "== a");
    LogFile b(folder / "b.log", "== b");
    VIOSFM_LOG(DEBUG) << "to both";
  }
  for (const char* name : {"a.log", "b.log"}) {
    const std::vector<std::string> lines = Lines(ReadTextFile(folder / name));
    ASSERT_GE(lines.size(), 2u);
    EXPECT_EQ(lines.front(), std::string("== ") + name[0]);
    EXPECT_EQ(lines.back().substr(25), " to both");
  }
}

TEST(LogMessage, AConsoleLineLongerThanTheWidthIsBrokenAtSpaces) {
  const LogLevelGuard level(LogLevel::kINFO);
  ::testing::internal::CaptureStderr();
  std::string long_text;
  for (int i = 0; i < 40; ++i) long_text += "word" + std::to_string(i) + " ";
  VIOSFM_LOG(INFO) << long_text;
  const std::vector<std::string> shown = Lines(::testing::internal::GetCapturedStderr());
  ASSERT_GT(shown.size(), 1u);
  for (const std::string& line : shown) EXPECT_LE(line.size(), kMaxConsoleLineLength) << line;
  EXPECT_EQ(shown[1].substr(0, 2), "  ");
}

TEST(WrapLines, BreaksAtSpacesAndIndents) {
  EXPECT_EQ(WrapLines("aaa bbb ccc ddd", 7), "aaa bbb\n  ccc\n  ddd");
  EXPECT_EQ(WrapLines("short\nlines stay\n", 20), "short\nlines stay\n");
  EXPECT_EQ(WrapLines(std::string(30, 'x') + " y", 10), std::string(30, 'x') + "\n  y");
}

}  // namespace
}  // namespace viosfm

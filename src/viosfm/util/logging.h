// Minimal thread-safe logging to stderr, and to a run's log file.
//   VIOSFM_LOG(INFO) << "registered " << n << " images";
// Levels: DEBUG < INFO < WARNING < ERROR. Messages below the console's level
// (default INFO, see SetLogLevel) are not printed; an open LogFile takes
// every message at its own level (DEBUG by default) whatever the console's.
// The console shows a message up to LogDetails() (the short line), the log
// file all of it; a console line longer than kMaxConsoleLineLength is broken
// at spaces.
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

namespace viosfm {

enum class LogLevel { kDEBUG = 0, kINFO = 1, kWARNING = 2, kERROR = 3 };

// The console's widest line (characters).
inline constexpr size_t kMaxConsoleLineLength = 120;

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
// Parses "debug", "info", "warning", "error" (any case); throws InputError otherwise.
LogLevel ParseLogLevel(const std::string& name);

// Streamed into a message, it ends the console's part: what follows goes to
// the log file only.
//   VIOSFM_LOG(INFO) << "vio: offset 0.2 ms (kept)" << LogDetails() << "; residuals ...";
struct LogDetails {};

// A file that receives every log message at `level` and above while it is
// open, each line with its date and time and flushed as it is written (a
// killed process leaves its log up to then). It is appended to: `heading`
// first, then the console's lines printed since the process started or the
// last log file closed (at most kLogBacklogLines), then what is logged. Two
// open at once (two runs in one process) both receive every message.
class LogFile {
 public:
  static constexpr size_t kLogBacklogLines = 200;

  // Opens `path` for appending; throws InputError naming it if it cannot.
  explicit LogFile(const std::filesystem::path& path, const std::string& heading = "",
                   LogLevel level = LogLevel::kDEBUG);
  ~LogFile();
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_;
};

// Writes `text` into the open log files, if any, and not to the console:
// what the console shows in its own way (a progress bar's last state, a
// run's summary on stdout) or what only the log keeps (a section heading).
void WriteToLogFile(const std::string& text);
// A message at `level` into the open log files, if any (with its level and
// time, as a logged one), and not to the console.
void LogToFileOnly(LogLevel level, const std::string& text);

// `text` with every line longer than `width` broken at spaces, the
// continuation lines indented by two spaces (a word longer than the width
// stays whole).
std::string WrapLines(const std::string& text, size_t width = kMaxConsoleLineLength);

class LogMessage {
 public:
  LogMessage(LogLevel level, const char* file, int line);
  ~LogMessage();
  LogMessage(const LogMessage&) = delete;
  LogMessage& operator=(const LogMessage&) = delete;

  template <typename T>
  LogMessage& operator<<(const T& value) {
    if (enabled_) stream_ << value;
    return *this;
  }
  LogMessage& operator<<(LogDetails);

 private:
  bool enabled_;
  LogLevel level_;
  std::ostringstream stream_;
  // Where the console's part of the message ends (npos: all of it).
  size_t console_end_;
};

}  // namespace viosfm

#define VIOSFM_LOG(level) ::viosfm::LogMessage(::viosfm::LogLevel::k##level, __FILE__, __LINE__)

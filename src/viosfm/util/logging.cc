#include "viosfm/util/logging.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <deque>
#include <mutex>
#include <utility>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

// The files' level while no log file is open: above every message.
constexpr int kNoLogFile = static_cast<int>(LogLevel::kERROR) + 1;

std::atomic<int> g_log_level{static_cast<int>(LogLevel::kINFO)};
std::atomic<int> g_file_level{kNoLogFile};

// The open log files with their levels, and the console's lines kept for
// the next one while none is open.
struct LogSinks {
  std::mutex mutex;
  std::vector<std::pair<std::FILE*, int>> files;
  std::deque<std::string> backlog;

  // The lowest level of an open file (kNoLogFile if none).
  int MinLevel() const {
    int level = kNoLogFile;
    for (const auto& file : files) level = std::min(level, file.second);
    return level;
  }
};

LogSinks& Sinks() {
  static LogSinks sinks;
  return sinks;
}

const char* LevelTag(LogLevel level) {
  switch (level) {
    case LogLevel::kDEBUG: return "D";
    case LogLevel::kINFO: return "I";
    case LogLevel::kWARNING: return "W";
    case LogLevel::kERROR: return "E";
  }
  return "?";
}

// The console's "HH:MM:SS" and the file's "YYYY-MM-DD HH:MM:SS.mmm", local time.
struct Stamps {
  char console[16];
  char file[32];
};

Stamps StampsNow() {
  const auto now = std::chrono::system_clock::now();
  const auto t = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  localtime_r(&t, &tm);
  Stamps stamps;
  std::strftime(stamps.console, sizeof(stamps.console), "%H:%M:%S", &tm);
  char date[24];
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M:%S", &tm);
  std::snprintf(stamps.file, sizeof(stamps.file), "%s.%03d", date, static_cast<int>(ms));
  return stamps;
}

void WriteAndFlush(std::FILE* file, const std::string& text) {
  std::fwrite(text.data(), 1, text.size(), file);
  if (text.empty() || text.back() != '\n') std::fputc('\n', file);
  std::fflush(file);
}

}  // namespace

void SetLogLevel(LogLevel level) {
  g_log_level = static_cast<int>(level);
}
LogLevel GetLogLevel() {
  return static_cast<LogLevel>(g_log_level.load());
}

LogLevel ParseLogLevel(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "debug") return LogLevel::kDEBUG;
  if (lower == "info") return LogLevel::kINFO;
  if (lower == "warning") return LogLevel::kWARNING;
  if (lower == "error") return LogLevel::kERROR;
  throw InputError("unknown log level '" + name + "' (expected debug, info, warning or error)");
}

LogFile::LogFile(const std::filesystem::path& path, const std::string& heading, LogLevel level)
    : path_(path), file_(std::fopen(path.c_str(), "ae")) {
  if (file_ == nullptr) throw InputError(path.string(), 0, "cannot open the log file for writing");
  LogSinks& sinks = Sinks();
  std::lock_guard<std::mutex> lock(sinks.mutex);
  if (!heading.empty()) WriteAndFlush(file_, heading);
  if (sinks.files.empty()) {
    for (const std::string& line : sinks.backlog) std::fputs(line.c_str(), file_);
    sinks.backlog.clear();
    std::fflush(file_);
  }
  sinks.files.emplace_back(file_, static_cast<int>(level));
  g_file_level = sinks.MinLevel();
}

LogFile::~LogFile() {
  LogSinks& sinks = Sinks();
  std::lock_guard<std::mutex> lock(sinks.mutex);
  std::erase_if(sinks.files, [this](const auto& file) { return file.first == file_; });
  g_file_level = sinks.MinLevel();
  std::fclose(file_);
}

void WriteToLogFile(const std::string& text) {
  LogSinks& sinks = Sinks();
  std::lock_guard<std::mutex> lock(sinks.mutex);
  for (const auto& file : sinks.files) WriteAndFlush(file.first, text);
}

void LogToFileOnly(LogLevel level, const std::string& text) {
  const Stamps stamps = StampsNow();
  const std::string line = std::string(LevelTag(level)) + " " + stamps.file + " " + text;
  LogSinks& sinks = Sinks();
  std::lock_guard<std::mutex> lock(sinks.mutex);
  for (const auto& file : sinks.files) {
    if (static_cast<int>(level) >= file.second) WriteAndFlush(file.first, line);
  }
}

std::string WrapLines(const std::string& text, size_t width) {
  std::istringstream in(text);
  std::string out, line;
  bool first_line = true;
  while (std::getline(in, line)) {
    if (!first_line) out += '\n';
    first_line = false;
    std::string current;
    size_t at = 0;
    while (at < line.size()) {
      size_t end = line.find(' ', at);
      if (end == std::string::npos) end = line.size();
      const std::string word = line.substr(at, end - at);
      if (!current.empty() && current.size() + 1 + word.size() > width) {
        out += current + '\n';
        current = "  " + word;
      } else {
        current += (current.empty() && at == 0 ? "" : " ") + word;
      }
      at = end + 1;
    }
    out += current;
  }
  if (!text.empty() && text.back() == '\n') out += '\n';
  return out;
}

LogMessage::LogMessage(LogLevel level, const char* /*file*/, int /*line*/)
    : enabled_(static_cast<int>(level) >= std::min(g_log_level.load(), g_file_level.load())),
      level_(level),
      console_end_(std::string::npos) {}

LogMessage& LogMessage::operator<<(LogDetails) {
  if (enabled_ && console_end_ == std::string::npos) console_end_ = stream_.str().size();
  return *this;
}

LogMessage::~LogMessage() {
  if (!enabled_) return;
  const std::string text = stream_.str();
  const Stamps stamps = StampsNow();
  const bool to_console = static_cast<int>(level_) >= g_log_level.load();
  const std::string file_line =
      std::string(LevelTag(level_)) + " " + stamps.file + " " + text + "\n";
  LogSinks& sinks = Sinks();
  std::lock_guard<std::mutex> lock(sinks.mutex);
  if (to_console) {
    const std::string console_line =
        std::string(LevelTag(level_)) + " " + stamps.console + " " + text.substr(0, console_end_);
    std::fprintf(stderr, "%s\n", WrapLines(console_line).c_str());
    std::fflush(stderr);
  }
  for (const auto& file : sinks.files) {
    if (static_cast<int>(level_) >= file.second) WriteAndFlush(file.first, file_line);
  }
  if (sinks.files.empty() && to_console) {
    sinks.backlog.push_back(file_line);
    if (sinks.backlog.size() > LogFile::kLogBacklogLines) sinks.backlog.pop_front();
  }
}

}  // namespace viosfm

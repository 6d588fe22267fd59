#include "viosfm/util/logging.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <mutex>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

std::atomic<int> g_log_level{static_cast<int>(LogLevel::kINFO)};
std::mutex g_log_mutex;

const char* LevelTag(LogLevel level) {
  switch (level) {
    case LogLevel::kDEBUG: return "D";
    case LogLevel::kINFO: return "I";
    case LogLevel::kWARNING: return "W";
    case LogLevel::kERROR: return "E";
  }
  return "?";
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

LogMessage::LogMessage(LogLevel level, const char* /*file*/, int /*line*/)
    : enabled_(static_cast<int>(level) >= g_log_level.load()), level_(level) {}

LogMessage::~LogMessage() {
  if (!enabled_) return;
  const auto now = std::chrono::system_clock::now();
  const auto t = std::chrono::system_clock::to_time_t(now);
  std::tm tm{};
  localtime_r(&t, &tm);
  char stamp[16];
  std::strftime(stamp, sizeof(stamp), "%H:%M:%S", &tm);
  std::lock_guard<std::mutex> lock(g_log_mutex);
  std::fprintf(stderr, "%s %s %s\n", LevelTag(level_), stamp, stream_.str().c_str());
  std::fflush(stderr);
}

}  // namespace viosfm

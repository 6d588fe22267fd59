// Minimal thread-safe logging to stderr.
//   VIOSFM_LOG(INFO) << "registered " << n << " images";
// Levels: DEBUG < INFO < WARNING < ERROR. Messages below the global level
// (default INFO, see SetLogLevel) are dropped.
#pragma once

#include <sstream>
#include <string>

namespace viosfm {

enum class LogLevel { kDEBUG = 0, kINFO = 1, kWARNING = 2, kERROR = 3 };

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
// Parses "debug", "info", "warning", "error" (any case); throws InputError otherwise.
LogLevel ParseLogLevel(const std::string& name);

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

 private:
  bool enabled_;
  LogLevel level_;
  std::ostringstream stream_;
};

}  // namespace viosfm

#define VIOSFM_LOG(level) ::viosfm::LogMessage(::viosfm::LogLevel::k##level, __FILE__, __LINE__)

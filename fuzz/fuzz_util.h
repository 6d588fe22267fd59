// Helpers of the libFuzzer targets in fuzz/ (see docs/robustness.md).
//
// Every reader in io/ takes a path, so a fuzzer writes its input to a file in
// a scratch folder of its own (in /dev/shm when there is one) and calls the
// reader. A reader may throw InputError on any input: that is the expected
// answer to bad input. Anything else that escapes (InternalError from a
// VIOSFM_CHECK, std::bad_alloc, a std::out_of_range, ...) ends the process
// through std::terminate and libFuzzer reports it as a crash, as it does
// AddressSanitizer and UndefinedBehaviorSanitizer findings.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm::fuzz {

// A scratch folder for this process, created on first use and emptied by
// the caller between inputs as needed.
inline const std::filesystem::path& ScratchFolder() {
  static const std::filesystem::path folder = [] {
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm")
                                           ? std::filesystem::path("/dev/shm")
                                           : std::filesystem::temp_directory_path();
    std::filesystem::path path = base / ("viosfm_fuzz_" + std::to_string(getpid()));
    std::filesystem::create_directories(path);
    // Readers log warnings (repeated stamps, ...) on valid input: keep the
    // fuzzer's output to its own statistics.
    SetLogLevel(LogLevel::kERROR);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(ScratchFolder(), ignored);
    });
    return path;
  }();
  return folder;
}

inline void WriteBytes(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string_view AsText(const uint8_t* data, size_t size) {
  return std::string_view(reinterpret_cast<const char*>(data), size);
}

// The separator between the files of a multi-file input (a COLMAP model's
// three files, a camchain and its IMU file). The seed corpus uses it too.
inline constexpr std::string_view kFileSeparator = "\n#--viosfm-fuzz-next-file--\n";

// Splits `input` into exactly `count` parts at kFileSeparator (missing parts
// are empty, extra separators stay in the last part).
inline std::vector<std::string_view> SplitFiles(std::string_view input, size_t count) {
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < count) {
    const size_t at = input.find(kFileSeparator);
    if (at == std::string_view::npos) break;
    parts.push_back(input.substr(0, at));
    input.remove_prefix(at + kFileSeparator.size());
  }
  parts.push_back(input);
  parts.resize(count);
  return parts;
}

// Runs `read`; an InputError is the expected answer to bad input.
template <typename Function>
bool AcceptsInput(Function read) {
  try {
    read();
    return true;
  } catch (const InputError&) {
    return false;
  }
}

// A property that must hold for every accepted input (a round trip): a
// violation is reported as a crash.
inline void Require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "property violated: %s\n", what);
    std::abort();
  }
}

}  // namespace viosfm::fuzz

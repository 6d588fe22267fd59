#include "viosfm/util/errors.h"

#include <filesystem>

namespace viosfm {
namespace {

std::string FormatInputError(const std::string& path, int64_t line, const std::string& what) {
  if (path.empty()) return what;
  if (line > 0) return path + ":" + std::to_string(line) + ": " + what;
  return path + ": " + what;
}

}  // namespace

InputError::InputError(const std::string& path, int64_t line, const std::string& what)
    : std::runtime_error(FormatInputError(path, line, what)), path_(path), line_(line) {}

TopLevelError DescribeTopLevelError(const std::exception& error) {
  if (dynamic_cast<const InputError*>(&error) != nullptr) {
    return {kExitInputError, std::string("error: ") + error.what()};
  }
  if (const auto* fs_error = dynamic_cast<const std::filesystem::filesystem_error*>(&error)) {
    // "error: <path>: cannot create directories: Not a directory"
    std::string paths = fs_error->path1().string();
    if (!fs_error->path2().empty()) paths += " -> " + fs_error->path2().string();
    std::string what = fs_error->what();
    // libstdc++: "filesystem error: <operation>: <reason> [path1] [path2]".
    const std::string prefix = "filesystem error: ";
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    if (const size_t bracket = what.find(" ["); bracket != std::string::npos) what.resize(bracket);
    return {kExitInputError, "error: " + (paths.empty() ? std::string() : paths + ": ") + what};
  }
  return {kExitInternalError, std::string("internal error: ") + error.what()};
}

namespace internal {

CheckFailure::CheckFailure(const char* file, int line, const char* expression) {
  stream_ << "Check failed at " << file << ":" << line << ": " << expression << " ";
}

CheckFailure::~CheckFailure() noexcept(false) {
  throw InternalError(stream_.str());
}

}  // namespace internal
}  // namespace viosfm

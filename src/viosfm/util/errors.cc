#include "viosfm/util/errors.h"

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

namespace internal {

CheckFailure::CheckFailure(const char* file, int line, const char* expression) {
  stream_ << "Check failed at " << file << ":" << line << ": " << expression << " ";
}

CheckFailure::~CheckFailure() noexcept(false) {
  throw InternalError(stream_.str());
}

}  // namespace internal
}  // namespace viosfm

// Error types and invariant checks.
//
// Three kinds of failure (see docs/design.md):
//  - bad user input throws InputError, whose message names the file, the
//    line (when there is one) and what was expected;
//  - broken internal invariants use VIOSFM_CHECK, which throws InternalError
//    (never aborts or exits: library code leaves ending the process to main);
//  - failures that can happen on good input are returned as a status by the
//    stage that meets them.
#pragma once

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

namespace viosfm {

// Bad input: a missing or malformed file, an unknown option value, ...
class InputError : public std::runtime_error {
 public:
  // "path:line: what" (line > 0), "path: what" (line == 0) or "what" (empty path).
  InputError(const std::string& path, int64_t line, const std::string& what);
  explicit InputError(const std::string& what) : InputError("", 0, what) {}

  const std::string& path() const { return path_; }
  int64_t line() const { return line_; }

 private:
  std::string path_;
  int64_t line_ = 0;
};

// A broken invariant inside the library: a bug, not bad input.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// What the viosfm command does with an exception that reaches main: the
// line to print and the exit code. Bad input (InputError) and a
// std::filesystem error (a path that cannot be read, created or renamed: a
// missing permission, a file where a folder is expected, a full disk) exit
// with 2 and name the path(s); anything else is an internal error, exit 3.
struct TopLevelError {
  int exit_code = 3;
  std::string message;  // "error: ..." or "internal error: ..."
};
TopLevelError DescribeTopLevelError(const std::exception& error);

inline constexpr int kExitInputError = 2;
inline constexpr int kExitInternalError = 3;

namespace internal {

// Collects a message with operator<< and throws InternalError when destroyed.
class CheckFailure {
 public:
  CheckFailure(const char* file, int line, const char* expression);
  ~CheckFailure() noexcept(false);
  CheckFailure(const CheckFailure&) = delete;
  CheckFailure& operator=(const CheckFailure&) = delete;

  template <typename T>
  CheckFailure& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  std::ostringstream stream_;
};

}  // namespace internal
}  // namespace viosfm

// VIOSFM_CHECK(cond) << "optional context"; throws InternalError if !cond.
#define VIOSFM_CHECK(condition) \
  if (condition) {              \
  } else                        \
    ::viosfm::internal::CheckFailure(__FILE__, __LINE__, #condition)

#define VIOSFM_CHECK_OP(op, a, b) VIOSFM_CHECK((a)op(b)) << "(" << (a) << " vs " << (b) << ") "
#define VIOSFM_CHECK_EQ(a, b) VIOSFM_CHECK_OP(==, a, b)
#define VIOSFM_CHECK_NE(a, b) VIOSFM_CHECK_OP(!=, a, b)
#define VIOSFM_CHECK_LT(a, b) VIOSFM_CHECK_OP(<, a, b)
#define VIOSFM_CHECK_LE(a, b) VIOSFM_CHECK_OP(<=, a, b)
#define VIOSFM_CHECK_GT(a, b) VIOSFM_CHECK_OP(>, a, b)
#define VIOSFM_CHECK_GE(a, b) VIOSFM_CHECK_OP(>=, a, b)

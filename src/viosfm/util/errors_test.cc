#include "viosfm/util/errors.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <system_error>

namespace viosfm {
namespace {

TEST(InputError, NamesFileAndLine) {
  const InputError error("data.csv", 12, "expected 7 columns, found 3");
  EXPECT_STREQ(error.what(), "data.csv:12: expected 7 columns, found 3");
  EXPECT_EQ(error.path(), "data.csv");
  EXPECT_EQ(error.line(), 12);
  EXPECT_STREQ(InputError("a.yaml", 0, "missing key").what(), "a.yaml: missing key");
  EXPECT_STREQ(InputError("plain").what(), "plain");
}

TEST(Check, ThrowsInternalErrorWithContext) {
  EXPECT_NO_THROW(VIOSFM_CHECK(1 + 1 == 2));
  try {
    const int a = 3;
    VIOSFM_CHECK_EQ(a, 4) << "context";
    FAIL() << "no throw";
  } catch (const InternalError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(3 vs 4)"), std::string::npos) << what;
    EXPECT_NE(what.find("context"), std::string::npos) << what;
    EXPECT_NE(what.find("errors_test.cc"), std::string::npos) << what;
  }
}

TEST(DescribeTopLevelError, InputAndFilesystemErrorsExit2InternalErrors3) {
  const TopLevelError input = DescribeTopLevelError(InputError("a.csv", 3, "bad row"));
  EXPECT_EQ(input.exit_code, 2);
  EXPECT_EQ(input.message, "error: a.csv:3: bad row");

  // A real filesystem error: a folder below a regular file cannot be made.
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("viosfm_errors_test_" + std::to_string(getpid()));
  std::ofstream(file) << "x";
  try {
    std::filesystem::create_directories(file / "sub");
    FAIL() << "no filesystem error";
  } catch (const std::filesystem::filesystem_error& error) {
    const TopLevelError described = DescribeTopLevelError(error);
    EXPECT_EQ(described.exit_code, 2);
    EXPECT_EQ(described.message.rfind("error: " + (file / "sub").string() + ": ", 0), 0u)
        << described.message;
    EXPECT_EQ(described.message.find('['), std::string::npos) << described.message;
  }
  std::filesystem::remove(file);
  const std::filesystem::filesystem_error two_paths(
      "cannot rename", "/a/b", "/c/d", std::make_error_code(std::errc::permission_denied));
  EXPECT_EQ(DescribeTopLevelError(two_paths).message,
            "error: /a/b -> /c/d: cannot rename: Permission denied");

  const TopLevelError internal = DescribeTopLevelError(InternalError("Check failed"));
  EXPECT_EQ(internal.exit_code, 3);
  EXPECT_EQ(internal.message, "internal error: Check failed");
  EXPECT_EQ(DescribeTopLevelError(std::runtime_error("boom")).exit_code, 3);
}

}  // namespace
}  // namespace viosfm

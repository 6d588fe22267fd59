#include "viosfm/util/errors.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace viosfm

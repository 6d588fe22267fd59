#include "viosfm/util/string_util.h"

#include <gtest/gtest.h>

namespace viosfm {
namespace {

TEST(StringUtil, SplitTrimParse) {
  EXPECT_EQ(Trim("  a b \r\n"), "a b");
  const auto parts = Split("1,2,,3", ",");
  ASSERT_EQ(parts.size(), 4u);
  EXPECT_EQ(parts[2], "");
  EXPECT_EQ(Split("a  b\tc", " \t", true).size(), 3u);
  EXPECT_EQ(ParseDouble(" 1.5e-3 "), 1.5e-3);
  EXPECT_EQ(ParseDouble("+2"), 2.0);
  EXPECT_FALSE(ParseDouble("1.5x"));
  EXPECT_FALSE(ParseDouble(""));
  EXPECT_EQ(ParseInt("-42"), -42);
  EXPECT_FALSE(ParseInt("4.2"));
  EXPECT_TRUE(StartsWith("#comment", "#"));
  EXPECT_TRUE(EndsWith("a.png", ".png"));
  EXPECT_EQ(ToLower("RadTan"), "radtan");
}

}  // namespace
}  // namespace viosfm

#include "viosfm/util/timestamp.h"

#include <gtest/gtest.h>

namespace viosfm {
namespace {

TEST(Timestamp, ParsesDecimalSecondsExactly) {
  EXPECT_EQ(ParseSecondsToNs("1403715273.262142976"), 1403715273262142976);
  EXPECT_EQ(ParseSecondsToNs("1305031102.175304"), 1305031102175304000);
  EXPECT_EQ(ParseSecondsToNs("12"), 12000000000);
  EXPECT_EQ(ParseSecondsToNs("-0.5"), -500000000);
  EXPECT_EQ(ParseSecondsToNs(".25"), 250000000);
  EXPECT_EQ(ParseSecondsToNs("0.0000000015"), 2);  // rounds the 10th digit
  EXPECT_EQ(ParseSecondsToNs("0.0000000014"), 1);
  EXPECT_FALSE(ParseSecondsToNs(""));
  EXPECT_FALSE(ParseSecondsToNs("1.2.3"));
  EXPECT_FALSE(ParseSecondsToNs("abc"));
  EXPECT_FALSE(ParseSecondsToNs("1e9"));
}

// The largest stamps an int64 holds parse exactly; one nanosecond more (or a
// rounding digit that carries past it) is rejected, never wrapped around.
TEST(Timestamp, SecondsBeyondInt64AreRejectedNotWrapped) {
  EXPECT_EQ(ParseSecondsToNs("9223372036.854775807"), INT64_MAX);
  EXPECT_EQ(ParseSecondsToNs("-9223372036.854775807"), -INT64_MAX);
  EXPECT_EQ(ParseSecondsToNs("9223372036.8547758074"), INT64_MAX);  // rounds down
  EXPECT_FALSE(ParseSecondsToNs("9223372036.854775808"));
  EXPECT_FALSE(ParseSecondsToNs("9223372036.8547758075"));  // rounds up past the limit
  EXPECT_FALSE(ParseSecondsToNs("9223372037"));
  EXPECT_FALSE(ParseSecondsToNs("9999999999.999999999"));  // passed the old digit-count guard
  EXPECT_FALSE(ParseSecondsToNs("100000000000000000000000"));
  EXPECT_FALSE(ParseSecondsToNs("-100000000000000000000000.5"));
  EXPECT_FALSE(ParseNs("9223372036854775808"));
  EXPECT_EQ(ParseNs("-9223372036854775808"), INT64_MIN);
}

TEST(Timestamp, FormatsRoundTrip) {
  EXPECT_EQ(FormatNsAsSeconds(1403715273262142976), "1403715273.262142976");
  EXPECT_EQ(FormatNsAsSeconds(1403715273262142976, 6), "1403715273.262143");
  EXPECT_EQ(FormatNsAsSeconds(5, 0), "0");
  EXPECT_EQ(FormatNsAsSeconds(-500000000, 3), "-0.500");
  EXPECT_EQ(FormatNsAsSeconds(999999999, 3), "1.000");
  for (int64_t ns : {int64_t{0}, int64_t{1}, int64_t{-7}, int64_t{1305031102175304000}}) {
    EXPECT_EQ(ParseSecondsToNs(FormatNsAsSeconds(ns)), ns);
  }
}

TEST(Timestamp, ParsesIntegerNanoseconds) {
  EXPECT_EQ(ParseNs("1403715273262142976"), 1403715273262142976);
  EXPECT_FALSE(ParseNs("14037152.73"));
  EXPECT_FALSE(ParseNs(""));
  EXPECT_EQ(SecondsToNs(1.5), 1500000000);
}

}  // namespace
}  // namespace viosfm

// Timestamps are int64 nanoseconds everywhere. Only these helpers convert to
// and from the decimal seconds that some file formats use, digit-exactly.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace viosfm {

using timestamp_ns_t = int64_t;

inline constexpr int64_t kNanosecondsPerSecond = 1'000'000'000;

// The stamps viosfm accepts from files: |t| <= 2^62 ns, about 146 years
// either side of the epoch, so that the difference of any two stamps and a
// stamp moved by a clock offset fit an int64 (readers reject others with an
// InputError rather than let a later subtraction overflow).
inline constexpr timestamp_ns_t kMaxAbsTimestampNs = timestamp_ns_t{1} << 62;
inline bool IsTimestampInRange(timestamp_ns_t ns) {
  return ns >= -kMaxAbsTimestampNs && ns <= kMaxAbsTimestampNs;
}

inline double NsToSeconds(timestamp_ns_t ns) {
  return static_cast<double>(ns) * 1e-9;
}
// Rounds to the nearest nanosecond.
timestamp_ns_t SecondsToNs(double seconds);

// Parses decimal seconds ("1305031102.175304", "-0.5", "12") into ns exactly
// from the digits (no detour through double). Digits beyond 1 ns are rounded
// half away from zero. Returns nullopt if the text is not such a number or
// if it does not fit an int64 count of ns (beyond +-9223372036.854775807 s).
std::optional<timestamp_ns_t> ParseSecondsToNs(std::string_view text);
// Parses an integer count of nanoseconds ("1403715273262142976"); nullopt if
// it does not fit an int64.
std::optional<timestamp_ns_t> ParseNs(std::string_view text);

// Writes ns as decimal seconds with exactly `decimals` fractional digits
// (0..9), rounding half away from zero: 1403715273262142976 -> "1403715273.262142976".
std::string FormatNsAsSeconds(timestamp_ns_t ns, int decimals = 9);

}  // namespace viosfm

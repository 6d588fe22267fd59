// Timestamps are int64 nanoseconds everywhere. Only these helpers convert to
// and from the decimal seconds that some file formats use, digit-exactly.
#pragma once

#include <cstddef>
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

// "[first, last] s" with millisecond digits, for messages.
std::string FormatNsSpan(timestamp_ns_t first, timestamp_ns_t last);

// The index of the element of `items` (ordered by time) nearest in time to
// `t`, if it is at most `max_dt` away; of two equally near, the later.
// `stamp_of(item)` gives an element's stamp. The one time lookup of
// viosfm: poses at image stamps (scene/trajectory.h NearestPoseIndex),
// ground-truth states at image stamps.
template <class Items, class StampOf>
std::optional<size_t> NearestStampIndex(const Items& items, timestamp_ns_t t, timestamp_ns_t max_dt,
                                        StampOf stamp_of) {
  size_t low = 0;  // first element with a stamp >= t
  size_t high = items.size();
  while (low < high) {
    const size_t middle = low + (high - low) / 2;
    if (stamp_of(items[middle]) < t) {
      low = middle + 1;
    } else {
      high = middle;
    }
  }
  std::optional<size_t> best;
  timestamp_ns_t best_dt = max_dt;
  const auto consider = [&](size_t index) {
    const timestamp_ns_t stamp = stamp_of(items[index]);
    const timestamp_ns_t dt = stamp > t ? stamp - t : t - stamp;
    if (dt <= best_dt) {
      best_dt = dt;
      best = index;
    }
  };
  if (low > 0) consider(low - 1);
  if (low < items.size()) consider(low);
  return best;
}

}  // namespace viosfm

#include "viosfm/util/timestamp.h"

#include <charconv>
#include <cmath>

#include "viosfm/util/errors.h"

namespace viosfm {

timestamp_ns_t SecondsToNs(double seconds) {
  return std::llround(seconds * 1e9);
}

std::optional<timestamp_ns_t> ParseNs(std::string_view text) {
  int64_t value = 0;
  const auto* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) return std::nullopt;
  return value;
}

std::optional<timestamp_ns_t> ParseSecondsToNs(std::string_view text) {
  if (text.empty()) return std::nullopt;
  bool negative = false;
  size_t i = 0;
  if (text[0] == '-' || text[0] == '+') {
    negative = text[0] == '-';
    i = 1;
  }
  const size_t dot = text.find('.', i);
  const std::string_view int_part =
      text.substr(i, dot == std::string_view::npos ? text.npos : dot - i);
  const std::string_view frac_part =
      dot == std::string_view::npos ? std::string_view() : text.substr(dot + 1);
  if (int_part.empty() && frac_part.empty()) return std::nullopt;
  // Every step is checked: a stamp beyond +-(2^63 - 1) ns (about 292 years)
  // does not fit an int64 and is rejected, never wrapped.
  int64_t seconds = 0;
  bool overflow = false;
  for (char c : int_part) {
    if (c < '0' || c > '9') return std::nullopt;
    overflow = overflow || __builtin_mul_overflow(seconds, int64_t{10}, &seconds) ||
               __builtin_add_overflow(seconds, int64_t{c - '0'}, &seconds);
  }
  int64_t frac_ns = 0;
  int digits = 0;
  bool round_up = false;
  for (char c : frac_part) {
    if (c < '0' || c > '9') return std::nullopt;
    if (digits < 9) {
      frac_ns = frac_ns * 10 + (c - '0');
    } else if (digits == 9) {
      round_up = c >= '5';
    }
    ++digits;
  }
  for (int d = digits; d < 9; ++d) frac_ns *= 10;
  int64_t ns = 0;
  overflow = overflow || __builtin_mul_overflow(seconds, kNanosecondsPerSecond, &ns) ||
             __builtin_add_overflow(ns, frac_ns + (round_up ? 1 : 0), &ns);
  if (overflow) return std::nullopt;
  return negative ? -ns : ns;
}

std::string FormatNsAsSeconds(timestamp_ns_t ns, int decimals) {
  VIOSFM_CHECK(decimals >= 0 && decimals <= 9) << "decimals=" << decimals;
  const bool negative = ns < 0;
  uint64_t magnitude = negative ? static_cast<uint64_t>(-(ns + 1)) + 1 : static_cast<uint64_t>(ns);
  uint64_t unit = 1;
  for (int d = decimals; d < 9; ++d) unit *= 10;
  magnitude = (magnitude + unit / 2) / unit;  // round half away from zero
  uint64_t scale = 1;
  for (int d = 0; d < decimals; ++d) scale *= 10;
  std::string out = negative && magnitude != 0 ? "-" : "";
  out += std::to_string(magnitude / scale);
  if (decimals > 0) {
    std::string frac = std::to_string(magnitude % scale);
    out.push_back('.');
    out.append(decimals - frac.size(), '0');
    out.append(frac);
  }
  return out;
}

std::string FormatNsSpan(timestamp_ns_t first, timestamp_ns_t last) {
  std::string span = "[";
  span.append(FormatNsAsSeconds(first, 3)).append(", ").append(FormatNsAsSeconds(last, 3));
  span.append("] s");
  return span;
}

}  // namespace viosfm

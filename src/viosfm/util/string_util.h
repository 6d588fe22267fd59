// Small text helpers for the readers in io/.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace viosfm {

std::string_view Trim(std::string_view text);
// Splits on any of `delimiters`; with `skip_empty`, runs of delimiters count as one.
std::vector<std::string_view> Split(std::string_view text, std::string_view delimiters,
                                    bool skip_empty = false);
bool StartsWith(std::string_view text, std::string_view prefix);
bool EndsWith(std::string_view text, std::string_view suffix);
std::string ToLower(std::string_view text);

// `value` printed with a printf format holding one floating-point
// conversion ("%.2f"), up to 63 characters.
std::string FormatDouble(const char* format, double value);
// `value` as "%.17g": the shortest printf form that always reads back to
// the same double.
std::string FormatRoundTrip(double value);
// `value` with `decimals` decimals ("%.*f"); "n/a" when absent or not finite.
std::string FormatFixedOrNa(std::optional<double> value, int decimals);

// Whole-string numeric parses; nullopt if anything but the number is there.
std::optional<double> ParseDouble(std::string_view text);
std::optional<int64_t> ParseInt(std::string_view text);

}  // namespace viosfm

// Line-by-line reading of the text formats in io/: blank lines and lines
// starting with '#' (after trimming) are skipped, line numbers count from 1
// and are passed on so that errors can name them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace viosfm {

// The longest line the text readers take, bytes (1 MiB): a file is read a
// line at a time, so its size never sets the memory its reading takes.
inline constexpr size_t kMaxTextLineBytes = size_t{1} << 20;

// Calls visit(line_number, trimmed_line) for every data line of `path`.
// `what` names the file in errors ("IMU file does not exist"); a line
// longer than kMaxTextLineBytes is an InputError naming the file and line.
void ForEachDataLine(const std::filesystem::path& path, const std::string& what,
                     const std::function<void(int64_t, std::string_view)>& visit);

// The fields of a data line. With `delimiters` = "," every comma separates a
// field (empty fields kept) and fields are trimmed; with whitespace
// delimiters runs of them count as one.
std::vector<std::string_view> SplitFields(std::string_view line, std::string_view delimiters);

}  // namespace viosfm

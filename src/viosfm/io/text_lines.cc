#include "viosfm/io/text_lines.h"

#include <fstream>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

void ForEachDataLine(const std::filesystem::path& path, const std::string& what,
                     const std::function<void(int64_t, std::string_view)>& visit) {
  RequireFile(path, what);
  std::ifstream stream(path);
  if (!stream) throw InputError(path.string(), 0, "cannot open " + what + " for reading");
  // One line at a time, each at most kMaxTextLineBytes: the memory a file
  // takes while it is read does not grow with its size.
  std::vector<char> buffer(kMaxTextLineBytes + 1);
  int64_t line_number = 0;
  while (true) {
    stream.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const std::streamsize count = stream.gcount();
    if (count == 0 && !stream) break;  // end of file
    ++line_number;
    if (stream.fail() && !stream.eof()) {
      // getline filled the buffer without finding the end of the line.
      throw InputError(path.string(), line_number,
                       "line longer than " + std::to_string(kMaxTextLineBytes) +
                           " bytes: not a line of a " + what);
    }
    // gcount counts the delimiter that getline consumed.
    const size_t length = static_cast<size_t>(count) - (stream.eof() ? 0 : 1);
    const std::string_view text = Trim(std::string_view(buffer.data(), length));
    if (!text.empty() && text.front() != '#') visit(line_number, text);
    if (stream.eof()) break;
  }
  if (stream.bad()) throw InputError(path.string(), line_number, "read error");
}

std::vector<std::string_view> SplitFields(std::string_view line, std::string_view delimiters) {
  const bool whitespace = delimiters.find_first_not_of(" \t") == std::string_view::npos;
  std::vector<std::string_view> fields = Split(line, delimiters, /*skip_empty=*/whitespace);
  for (std::string_view& field : fields) field = Trim(field);
  return fields;
}

}  // namespace viosfm

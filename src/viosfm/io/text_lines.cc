#include "viosfm/io/text_lines.h"

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

void ForEachDataLine(const std::filesystem::path& path, const std::string& what,
                     const std::function<void(int64_t, std::string_view)>& visit) {
  RequireFile(path, what);
  std::ifstream stream(path);
  if (!stream) throw InputError(path.string(), 0, "cannot open " + what + " for reading");
  std::string line;
  int64_t line_number = 0;
  while (std::getline(stream, line)) {
    ++line_number;
    const std::string_view text = Trim(line);
    if (text.empty() || text.front() == '#') continue;
    visit(line_number, text);
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

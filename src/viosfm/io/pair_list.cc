#include "viosfm/io/pair_list.h"

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

constexpr std::string_view kWhitespace = " \t\r\v\f";

bool IsWritableName(const std::string& name) {
  return !name.empty() && name.find_first_of(kWhitespace) == std::string::npos &&
         name.find('\n') == std::string::npos && name.front() != '#';
}

}  // namespace

ImageNamePairList ReadImagePairList(const fs::path& path) {
  RequireFile(path, "image pair list");
  std::ifstream stream(path);
  if (!stream) throw InputError(path.string(), 0, "cannot open for reading");
  ImageNamePairList list;
  list.path = path;
  std::string line;
  int64_t line_number = 0;
  while (std::getline(stream, line)) {
    ++line_number;
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    const std::vector<std::string_view> fields = Split(trimmed, kWhitespace, /*skip_empty=*/true);
    if (fields.size() != 2) {
      throw InputError(path.string(), line_number,
                       "expected two image names \"name1 name2\", got " +
                           std::to_string(fields.size()) + " field(s): '" + std::string(trimmed) +
                           "'");
    }
    if (fields[0] == fields[1]) {
      throw InputError(path.string(), line_number,
                       "expected two different images, got '" + std::string(fields[0]) + "' twice");
    }
    list.pairs.push_back({std::string(fields[0]), std::string(fields[1]), line_number});
  }
  if (stream.bad()) throw InputError(path.string(), line_number, "read error");
  return list;
}

void WriteImagePairList(const fs::path& path, const std::vector<ImageNamePair>& pairs) {
  for (size_t i = 0; i < pairs.size(); ++i) {
    for (const std::string* name : {&pairs[i].name1, &pairs[i].name2}) {
      if (!IsWritableName(*name)) {
        throw InputError(path.string(), 0,
                         "pair " + std::to_string(i) + ": image name '" + *name +
                             "' cannot be written to a pair list (empty, starts with '#' or "
                             "contains whitespace)");
      }
    }
  }
  WriteFileAtomically(path, [&](std::ostream& out) {
    for (const ImageNamePair& pair : pairs) out << pair.name1 << ' ' << pair.name2 << '\n';
  });
}

}  // namespace viosfm

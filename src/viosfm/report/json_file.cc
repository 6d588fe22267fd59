#include "viosfm/report/json_file.h"

#include <algorithm>
#include <cstdint>
#include <string>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  const std::string text = ReadTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // Line of the byte where parsing stopped.
    const size_t end = std::min(static_cast<size_t>(e.byte), text.size());
    const int64_t line = 1 + std::count(text.begin(), text.begin() + end, '\n');
    throw InputError(path.string(), line, std::string("expected valid JSON: ") + e.what());
  }
}

}  // namespace viosfm

#include "viosfm/util/option_fields.h"

#include <cerrno>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <sstream>

namespace viosfm {
namespace {

// Parses the whole of `text` with strtoll/strtoull/strtod; InputError if
// any of it is left over or the value is out of range.
template <class T, class Parse>
T ParseWhole(const std::string& text, const char* expected, Parse parse) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const auto value = parse(begin, &end);
  if (text.empty() || end != begin + text.size() || errno == ERANGE) {
    throw InputError(std::string("expected ") + expected);
  }
  return static_cast<T>(value);
}

}  // namespace

std::string OptionText(bool value) {
  return value ? "true" : "false";
}
std::string OptionText(int value) {
  return std::to_string(value);
}
std::string OptionText(int64_t value) {
  return std::to_string(value);
}
std::string OptionText(uint64_t value) {
  return std::to_string(value);
}
std::string OptionText(double value) {
  std::ostringstream stream;
  stream << std::setprecision(10) << value;
  return stream.str();
}
std::string OptionText(const std::string& value) {
  return value;
}
std::string OptionText(const std::filesystem::path& value) {
  return value.string();
}
std::string OptionText(const std::vector<int>& values) {
  std::string text;
  for (const int value : values) {
    if (!text.empty()) text += ',';
    text += std::to_string(value);
  }
  return text;
}

void ParseOptionText(const std::string& text, bool* value) {
  if (text == "true" || text == "1") {
    *value = true;
  } else if (text == "false" || text == "0") {
    *value = false;
  } else {
    throw InputError("expected true or false");
  }
}
void ParseOptionText(const std::string& text, int* value) {
  const int64_t wide = ParseWhole<int64_t>(
      text, "an integer", [](const char* s, char** end) { return std::strtoll(s, end, 10); });
  if (wide < std::numeric_limits<int>::min() || wide > std::numeric_limits<int>::max()) {
    throw InputError("expected an integer of at most 10 digits");
  }
  *value = static_cast<int>(wide);
}
void ParseOptionText(const std::string& text, int64_t* value) {
  *value = ParseWhole<int64_t>(text, "an integer",
                               [](const char* s, char** end) { return std::strtoll(s, end, 10); });
}
void ParseOptionText(const std::string& text, uint64_t* value) {
  if (!text.empty() && text[0] == '-') throw InputError("expected an integer >= 0");
  *value = ParseWhole<uint64_t>(
      text, "an integer >= 0", [](const char* s, char** end) { return std::strtoull(s, end, 10); });
}
void ParseOptionText(const std::string& text, double* value) {
  *value = ParseWhole<double>(text, "a number",
                              [](const char* s, char** end) { return std::strtod(s, end); });
}
void ParseOptionText(const std::string& text, std::string* value) {
  *value = text;
}
void ParseOptionText(const std::string& text, std::filesystem::path* value) {
  *value = text;
}
void ParseOptionText(const std::string& text, std::vector<int>* values) {
  std::vector<int> parsed;
  std::string item;
  std::istringstream stream(text);
  while (std::getline(stream, item, ',')) {
    int value = 0;
    try {
      ParseOptionText(item, &value);
    } catch (const InputError&) {
      throw InputError("expected comma-separated integers");
    }
    parsed.push_back(value);
  }
  *values = parsed;
}

}  // namespace viosfm

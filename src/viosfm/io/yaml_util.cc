#include "viosfm/io/yaml_util.h"

#include <cmath>
#include <map>
#include <optional>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

// Nesting deeper, or more nodes (aliases counted each time they are used),
// than this is not a calibration file.
constexpr int kMaxYamlDepth = 64;
constexpr int64_t kMaxYamlNodes = 1'000'000;

// YAML forbids a key twice in one map; yaml-cpp keeps both and answers with
// the first, so a file that says two things would be read as one of them.
void CheckNoDuplicateKeys(const fs::path& path, const YAML::Node& node, int depth,
                          int64_t* num_nodes) {
  if (depth > kMaxYamlDepth || ++*num_nodes > kMaxYamlNodes) {
    throw InputError(path.string(), YamlLine(node),
                     "nested deeper than " + std::to_string(kMaxYamlDepth) +
                         " levels or more than " + std::to_string(kMaxYamlNodes) +
                         " nodes: not a calibration file");
  }
  if (node.IsMap()) {
    std::map<std::string, int64_t> line_of_key;
    for (const auto& entry : node) {
      const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "(a non-scalar key)";
      const auto [it, inserted] = line_of_key.emplace(key, YamlLine(entry.first));
      if (!inserted) {
        throw InputError(path.string(), YamlLine(entry.first),
                         "duplicate key '" + key + "' (first on line " +
                             std::to_string(it->second) + "): a key may appear once in a map");
      }
      CheckNoDuplicateKeys(path, entry.second, depth + 1, num_nodes);
    }
  } else if (node.IsSequence()) {
    for (const YAML::Node& element : node) {
      CheckNoDuplicateKeys(path, element, depth + 1, num_nodes);
    }
  }
}

}  // namespace

YAML::Node LoadYamlFile(const fs::path& path) {
  RequireFile(path);
  // A calibration is a few kB; the file is read whole.
  constexpr uintmax_t kMaxYamlBytes = 16 << 20;
  if (fs::file_size(path) > kMaxYamlBytes) {
    throw InputError(path.string(), 0,
                     "a YAML file of " + std::to_string(fs::file_size(path)) +
                         " bytes: more than the 16 MiB a calibration file may have");
  }
  std::string text = ReadTextFile(path);
  // OpenCV's FileStorage writes "%YAML:1.0", which is not a valid YAML
  // directive; turn it into a comment of the same line.
  const size_t start = text.find_first_not_of(" \t\r\n");
  if (start != std::string::npos && text.compare(start, 6, "%YAML:") == 0) text[start] = '#';
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& error) {
    throw InputError(path.string(), error.mark.is_null() ? 0 : error.mark.line + 1,
                     "invalid YAML: " + error.msg);
  }
  int64_t num_nodes = 0;
  CheckNoDuplicateKeys(path, root, 0, &num_nodes);
  return root;
}

int64_t YamlLine(const YAML::Node& node) {
  if (!node.IsDefined()) return 0;
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

YamlMap::YamlMap(const fs::path& path, const YAML::Node& node) : path_(path), node_(node) {
  if (!node_.IsMap()) {
    throw InputError(path_.string(), YamlLine(node_), "expected a YAML map of key: value entries");
  }
}

YamlMap YamlMap::Load(const fs::path& path) {
  return YamlMap(path, LoadYamlFile(path));
}

bool YamlMap::Has(const std::string& key) const {
  const YAML::Node& node = node_;
  const YAML::Node value = node[key];
  return value.IsDefined() && !value.IsNull();
}

void YamlMap::Fail(const std::string& key, const std::string& what) const {
  const YAML::Node& node = node_;
  const YAML::Node value = node[key];
  const int64_t line = value.IsDefined() ? YamlLine(value) : YamlLine(node_);
  throw InputError(path_.string(), line, "'" + key + "': " + what);
}

YAML::Node YamlMap::Get(const std::string& key) const {
  if (!Has(key)) Fail(key, "required key is missing");
  const YAML::Node& node = node_;
  return node[key];
}

double YamlMap::ToDouble(const std::string& key, const YAML::Node& node) const {
  std::optional<double> value;
  if (node.IsScalar()) value = ParseDouble(node.Scalar());
  if (!value || !std::isfinite(*value)) {
    throw InputError(path_.string(), YamlLine(node),
                     "'" + key + "': expected a finite number" +
                         (node.IsScalar() ? ", got '" + node.Scalar() + "'" : std::string()));
  }
  return *value;
}

std::vector<double> YamlMap::ToDoubles(const std::string& key, const YAML::Node& node) const {
  if (!node.IsSequence()) {
    throw InputError(path_.string(), YamlLine(node), "'" + key + "': expected a list [a, b, ...]");
  }
  std::vector<double> values;
  for (const YAML::Node& element : node) values.push_back(ToDouble(key, element));
  return values;
}

double YamlMap::GetDouble(const std::string& key) const {
  return ToDouble(key, Get(key));
}

std::string YamlMap::GetString(const std::string& key) const {
  const YAML::Node value = Get(key);
  if (!value.IsScalar()) Fail(key, "expected a single value");
  return value.Scalar();
}

std::vector<double> YamlMap::GetDoubles(const std::string& key, int expected_size) const {
  const std::vector<double> values = ToDoubles(key, Get(key));
  if (expected_size >= 0 && static_cast<int>(values.size()) != expected_size) {
    Fail(key, "expected " + std::to_string(expected_size) + " numbers, got " +
                  std::to_string(values.size()));
  }
  return values;
}

YamlMap YamlMap::GetMap(const std::string& key) const {
  const YAML::Node value = Get(key);
  if (!value.IsMap()) Fail(key, "expected a map of key: value entries");
  return YamlMap(path_, value);
}

Eigen::Matrix4d YamlMap::GetMatrix4(const std::string& key) const {
  const YAML::Node value = Get(key);
  std::vector<double> data;
  if (value.IsMap()) {
    const YamlMap matrix(path_, value);
    const std::vector<double> data_values = matrix.GetDoubles("data");
    for (const char* dimension : {"rows", "cols"}) {
      if (matrix.Has(dimension) && matrix.GetDouble(dimension) != 4.0) {
        matrix.Fail(dimension,
                    std::string("expected 4 for the ") + dimension + " of '" + key + "'");
      }
    }
    data = data_values;
  } else if (value.IsSequence() && value.size() == 4 && value[0].IsSequence()) {
    for (const YAML::Node& row : value) {
      const std::vector<double> row_values = ToDoubles(key, row);
      if (row_values.size() != 4) {
        throw InputError(path_.string(), YamlLine(row),
                         "'" + key + "': expected rows of 4 numbers");
      }
      data.insert(data.end(), row_values.begin(), row_values.end());
    }
  } else {
    data = ToDoubles(key, value);
  }
  if (data.size() != 16) {
    Fail(key, "expected a 4x4 matrix (16 numbers, row-major), got " + std::to_string(data.size()) +
                  " numbers");
  }
  Eigen::Matrix4d matrix;
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) matrix(row, col) = data[4 * row + col];
  }
  return matrix;
}

}  // namespace viosfm

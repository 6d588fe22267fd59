// YAML helpers for the readers in io/ (internal: this header includes
// yaml-cpp, which only viosfm_io links). Every accessor throws InputError
// naming the file, the line of the offending node and what was expected.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace viosfm {

// Parses a YAML file. An OpenCV-style first line "%YAML:1.0" (as in EuRoC's
// sensor.yaml files) is read as a comment, so line numbers are unchanged.
YAML::Node LoadYamlFile(const std::filesystem::path& path);

// 1-based line of a node, 0 if unknown.
int64_t YamlLine(const YAML::Node& node);

// A wrapper of a parsed map that knows its file, for error messages.
class YamlMap {
 public:
  YamlMap(const std::filesystem::path& path, const YAML::Node& node);
  // Reads the file; its top level must be a map.
  static YamlMap Load(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  bool Has(const std::string& key) const;

  // Required keys: throw if absent or of the wrong kind.
  double GetDouble(const std::string& key) const;
  std::string GetString(const std::string& key) const;
  // A sequence of numbers; with expected_size >= 0 its length must match.
  std::vector<double> GetDoubles(const std::string& key, int expected_size = -1) const;
  // A 4x4 matrix given either as an OpenCV/Kalibr map {rows: 4, cols: 4,
  // data: [16 numbers, row-major]}, a flat list of 16 numbers, or a list of 4
  // rows of 4 numbers.
  Eigen::Matrix4d GetMatrix4(const std::string& key) const;
  // A nested map (e.g. Kalibr's "cam0:"); throws if absent or not a map.
  YamlMap GetMap(const std::string& key) const;

  // Throws InputError at the line of `key` (or of the map if absent).
  [[noreturn]] void Fail(const std::string& key, const std::string& what) const;

 private:
  YAML::Node Get(const std::string& key) const;
  double ToDouble(const std::string& key, const YAML::Node& node) const;
  std::vector<double> ToDoubles(const std::string& key, const YAML::Node& node) const;

  std::filesystem::path path_;
  YAML::Node node_;
};

}  // namespace viosfm

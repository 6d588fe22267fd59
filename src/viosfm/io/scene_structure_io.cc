#include "viosfm/io/scene_structure_io.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "viosfm/io/text_lines.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;
namespace {

constexpr size_t kNumColumns = 13;
constexpr const char* kColumnNames[kNumColumns] = {
    "id",       "region",   "floor",    "texture_id", "origin_x", "origin_y", "origin_z",
    "axis_u_x", "axis_u_y", "axis_u_z", "axis_v_x",   "axis_v_y", "axis_v_z"};

std::string ColumnLabel(size_t column) {
  return "column " + std::to_string(column + 1) + " (" + kColumnNames[column] + ")";
}

int ParseIntField(const fs::path& path, int64_t line, std::string_view field, size_t column) {
  const std::optional<int64_t> value = ParseInt(field);
  if (!value || *value < -1 || *value > 1'000'000'000) {
    throw InputError(
        path.string(), line,
        ColumnLabel(column) + ": expected an integer >= -1, got '" + std::string(field) + "'");
  }
  return static_cast<int>(*value);
}

double ParseNumberField(const fs::path& path, int64_t line, std::string_view field, size_t column) {
  const std::optional<double> value = ParseDouble(field);
  if (!value || !std::isfinite(*value)) {
    throw InputError(
        path.string(), line,
        ColumnLabel(column) + ": expected a finite number, got '" + std::string(field) + "'");
  }
  return *value;
}

}  // namespace

void WriteSceneStructure(const fs::path& path, const SceneStructure& structure) {
  WriteFileAtomically(path, [&](std::ostream& stream) {
    stream << '#';
    for (size_t column = 0; column < kNumColumns; ++column) {
      stream << (column == 0 ? "" : ",") << kColumnNames[column];
    }
    stream << " (metres, world frame)\n";
    for (const SceneStructureQuad& quad : structure) {
      VIOSFM_CHECK(quad.region.find(',') == std::string::npos) << quad.region;
      stream << quad.id << ',' << quad.region << ',' << quad.floor << ',' << quad.texture_id;
      for (const Eigen::Vector3d* vector : {&quad.origin, &quad.axis_u, &quad.axis_v}) {
        for (int k = 0; k < 3; ++k) stream << ',' << FormatRoundTrip((*vector)[k]);
      }
      stream << '\n';
    }
  });
}

SceneStructure ReadSceneStructure(const fs::path& path) {
  SceneStructure structure;
  ForEachDataLine(path, "scene structure file does not exist",
                  [&](int64_t line, std::string_view text) {
                    const std::vector<std::string_view> fields = SplitFields(text, ",");
                    if (fields.size() != kNumColumns) {
                      throw InputError(path.string(), line,
                                       "expected " + std::to_string(kNumColumns) +
                                           " comma-separated fields (id, region, floor, "
                                           "texture_id, origin xyz, axis_u xyz, axis_v xyz), got " +
                                           std::to_string(fields.size()));
                    }
                    SceneStructureQuad quad;
                    quad.id = ParseIntField(path, line, fields[0], 0);
                    quad.region = std::string(fields[1]);
                    quad.floor = ParseIntField(path, line, fields[2], 2);
                    quad.texture_id = ParseIntField(path, line, fields[3], 3);
                    Eigen::Vector3d* vectors[] = {&quad.origin, &quad.axis_u, &quad.axis_v};
                    for (int v = 0; v < 3; ++v) {
                      for (int k = 0; k < 3; ++k) {
                        const size_t column = 4 + 3 * v + k;
                        (*vectors[v])[k] = ParseNumberField(path, line, fields[column], column);
                      }
                    }
                    structure.push_back(std::move(quad));
                  });
  return structure;
}

}  // namespace viosfm

#include "viosfm/io/ply.h"

#include <bit>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

void AppendLittleEndian(uint64_t bits, size_t num_bytes, std::string* out) {
  for (size_t i = 0; i < num_bytes; ++i)
    out->push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
}

enum class ScalarType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<ScalarType> ParseScalarType(std::string_view name) {
  if (name == "char" || name == "int8") return ScalarType::kInt8;
  if (name == "uchar" || name == "uint8") return ScalarType::kUint8;
  if (name == "short" || name == "int16") return ScalarType::kInt16;
  if (name == "ushort" || name == "uint16") return ScalarType::kUint16;
  if (name == "int" || name == "int32") return ScalarType::kInt32;
  if (name == "uint" || name == "uint32") return ScalarType::kUint32;
  if (name == "float" || name == "float32") return ScalarType::kFloat32;
  if (name == "double" || name == "float64") return ScalarType::kFloat64;
  return std::nullopt;
}

size_t ScalarSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUint8: return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16: return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32: return 4;
    case ScalarType::kFloat64: return 8;
  }
  return 0;
}

// Decodes one binary scalar; `bytes` holds ScalarSize(type) bytes.
double DecodeScalar(ScalarType type, const char* bytes, bool big_endian) {
  const size_t size = ScalarSize(type);
  uint64_t bits = 0;
  for (size_t i = 0; i < size; ++i) {
    const size_t index = big_endian ? size - 1 - i : i;
    bits |= static_cast<uint64_t>(static_cast<uint8_t>(bytes[index])) << (8 * i);
  }
  switch (type) {
    case ScalarType::kInt8: return static_cast<int8_t>(bits);
    case ScalarType::kUint8: return static_cast<uint8_t>(bits);
    case ScalarType::kInt16: return static_cast<int16_t>(bits);
    case ScalarType::kUint16: return static_cast<uint16_t>(bits);
    case ScalarType::kInt32: return static_cast<int32_t>(bits);
    case ScalarType::kUint32: return static_cast<uint32_t>(bits);
    case ScalarType::kFloat32: return std::bit_cast<float>(static_cast<uint32_t>(bits));
    case ScalarType::kFloat64: return std::bit_cast<double>(bits);
  }
  return 0.0;
}

struct Property {
  std::string name;
  ScalarType type;
};

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

}  // namespace

void WritePlyPoints(const fs::path& path, const std::vector<Eigen::Vector3d>& xyz,
                    const std::vector<Vector3ub>& rgb, bool binary) {
  VIOSFM_CHECK(rgb.empty() || rgb.size() == xyz.size())
      << xyz.size() << " points but " << rgb.size() << " colours";
  const bool has_color = !rgb.empty();
  std::string header = "ply\n";
  header += binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
  header += "element vertex " + std::to_string(xyz.size()) + "\n";
  header += "property double x\nproperty double y\nproperty double z\n";
  if (has_color) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "end_header\n";

  std::string body;
  if (binary) {
    body.reserve(xyz.size() * (has_color ? 27 : 24));
    for (size_t i = 0; i < xyz.size(); ++i) {
      for (int k = 0; k < 3; ++k) AppendLittleEndian(std::bit_cast<uint64_t>(xyz[i][k]), 8, &body);
      if (has_color) {
        for (int k = 0; k < 3; ++k) body.push_back(static_cast<char>(rgb[i][k]));
      }
    }
  } else {
    std::ostringstream out;
    out.precision(17);
    for (size_t i = 0; i < xyz.size(); ++i) {
      out << xyz[i].x() << ' ' << xyz[i].y() << ' ' << xyz[i].z();
      if (has_color) {
        out << ' ' << static_cast<int>(rgb[i][0]) << ' ' << static_cast<int>(rgb[i][1]) << ' '
            << static_cast<int>(rgb[i][2]);
      }
      out << '\n';
    }
    body = out.str();
  }
  WriteFileAtomically(
      path,
      [&](std::ostream& stream) {
        stream.write(header.data(), static_cast<std::streamsize>(header.size()));
        stream.write(body.data(), static_cast<std::streamsize>(body.size()));
      },
      /*binary=*/true);
}

void WritePly(const fs::path& path, const Reconstruction& reconstruction, bool binary) {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<Vector3ub> rgb;
  xyz.reserve(reconstruction.NumPoints3D());
  rgb.reserve(reconstruction.NumPoints3D());
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    xyz.push_back(point3D.xyz);
    rgb.push_back(point3D.color);
  }
  WritePlyPoints(path, xyz, rgb, binary);
}

namespace {

// Reads a PLY file's vertices in named steps: the header (format, the vertex
// element's properties), which property feeds which value, then the ASCII
// or binary body.
class PlyReader {
 public:
  explicit PlyReader(const fs::path& path) : content_(ReadTextFile(path)), file_(path.string()) {}

  PlyPoints Read() {
    ReadHeader();
    MapProperties();
    if (*format_ == PlyFormat::kAscii) {
      ReadAsciiBody();
    } else {
      ReadBinaryBody();
    }
    return std::move(points_);
  }

 private:
  enum class Section { kNone, kVertex, kOther };

  // The next line without its end of line, or none at the end of the file.
  std::optional<std::string_view> NextLine() {
    if (offset_ >= content_.size()) return std::nullopt;
    size_t end = content_.find('\n', offset_);
    if (end == std::string::npos) end = content_.size();
    std::string_view line(content_.data() + offset_, end - offset_);
    offset_ = std::min(end + 1, content_.size());
    ++line_number_;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
  }

  void ReadHeader() {
    std::optional<std::string_view> line = NextLine();
    if (!line || Trim(*line) != "ply")
      throw InputError(file_, 1, "expected 'ply' (not a PLY file)");
    while (true) {
      line = NextLine();
      if (!line) {
        throw InputError(file_, line_number_, "expected 'end_header', found the end of the file");
      }
      const std::vector<std::string_view> tokens = Split(Trim(*line), " \t", true);
      if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
      if (tokens[0] == "end_header") break;
      if (tokens[0] == "format") {
        ReadFormat(tokens);
      } else if (tokens[0] == "element") {
        ReadElement(tokens);
      } else if (tokens[0] == "property") {
        ReadProperty(tokens);
      } else {
        throw InputError(file_, line_number_,
                         "unexpected header line '" + std::string(*line) + "'");
      }
    }
    if (!format_) throw InputError(file_, line_number_, "the header has no 'format' line");
    if (!seen_vertex_) throw InputError(file_, line_number_, "the header has no 'element vertex'");
  }

  void ReadFormat(const std::vector<std::string_view>& tokens) {
    if (tokens.size() != 3 || tokens[2] != "1.0") {
      throw InputError(file_, line_number_,
                       "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    }
    if (tokens[1] == "ascii") {
      format_ = PlyFormat::kAscii;
    } else if (tokens[1] == "binary_little_endian") {
      format_ = PlyFormat::kBinaryLittleEndian;
    } else if (tokens[1] == "binary_big_endian") {
      format_ = PlyFormat::kBinaryBigEndian;
    } else {
      throw InputError(file_, line_number_, "unknown PLY format '" + std::string(tokens[1]) + "'");
    }
  }

  void ReadElement(const std::vector<std::string_view>& tokens) {
    if (tokens.size() != 3) {
      throw InputError(file_, line_number_, "expected 'element <name> <count>'");
    }
    const std::optional<int64_t> count = ParseInt(tokens[2]);
    if (!count || *count < 0) {
      throw InputError(file_, line_number_,
                       "expected an element count, found '" + std::string(tokens[2]) + "'");
    }
    if (tokens[1] != "vertex") {
      section_ = Section::kOther;
      return;
    }
    if (section_ != Section::kNone) {
      throw InputError(file_, line_number_, "expected 'element vertex' as the first element");
    }
    section_ = Section::kVertex;
    seen_vertex_ = true;
    num_vertices_ = static_cast<uint64_t>(*count);
  }

  void ReadProperty(const std::vector<std::string_view>& tokens) {
    if (section_ == Section::kOther) return;  // elements after the vertices are ignored
    if (section_ == Section::kNone) {
      throw InputError(file_, line_number_, "expected 'element' before 'property'");
    }
    if (tokens.size() != 3) {
      throw InputError(file_, line_number_,
                       "expected 'property <scalar type> <name>' (list properties of "
                       "vertices are not supported)");
    }
    const std::optional<ScalarType> type = ParseScalarType(tokens[1]);
    if (!type) {
      throw InputError(file_, line_number_,
                       "unknown property type '" + std::string(tokens[1]) + "'");
    }
    properties_.push_back({std::string(tokens[2]), *type});
  }

  // Which property feeds which output value: 0-2 xyz, 3-5 rgb.
  void MapProperties() {
    static constexpr const char* kNames[6] = {"x", "y", "z", "red", "green", "blue"};
    for (size_t p = 0; p < properties_.size(); ++p) {
      for (int k = 0; k < 6; ++k) {
        if (properties_[p].name == kNames[k]) source_[k] = static_cast<int>(p);
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (source_[k] < 0) {
        throw InputError(file_, line_number_,
                         std::string("the vertex element has no property ") + kNames[k]);
      }
    }
    const int num_color = (source_[3] >= 0) + (source_[4] >= 0) + (source_[5] >= 0);
    if (num_color != 0 && num_color != 3) {
      throw InputError(file_, line_number_, "expected all of red, green, blue or none");
    }
    has_color_ = num_color == 3;
    values_.resize(properties_.size());
  }

  // The vertex of values_ into the points.
  void Store() {
    points_.xyz.emplace_back(values_[source_[0]], values_[source_[1]], values_[source_[2]]);
    if (!has_color_) return;
    Vector3ub color;
    for (int k = 0; k < 3; ++k) {
      const double value = values_[source_[3 + k]];
      if (!(value >= 0.0 && value <= 255.0)) {
        throw InputError(file_, *format_ == PlyFormat::kAscii ? line_number_ : 0,
                         "vertex " + std::to_string(points_.xyz.size() - 1) + ": colour " +
                             std::to_string(value) + " is not in [0, 255]");
      }
      color[k] = static_cast<uint8_t>(value);
    }
    points_.rgb.push_back(color);
  }

  void ReadAsciiBody() {
    for (uint64_t i = 0; i < num_vertices_; ++i) {
      const std::optional<std::string_view> line = NextLine();
      if (!line) {
        throw InputError(
            file_, line_number_,
            "expected " + std::to_string(num_vertices_) + " vertices, found " + std::to_string(i));
      }
      const std::vector<std::string_view> tokens = Split(Trim(*line), " \t", true);
      if (tokens.size() != properties_.size()) {
        throw InputError(file_, line_number_,
                         "expected " + std::to_string(properties_.size()) + " values for vertex " +
                             std::to_string(i) + ", found " + std::to_string(tokens.size()));
      }
      for (size_t p = 0; p < properties_.size(); ++p) {
        const std::optional<double> value = ParseDouble(tokens[p]);
        if (!value) {
          throw InputError(file_, line_number_,
                           "expected a number for property " + properties_[p].name + ", found '" +
                               std::string(tokens[p]) + "'");
        }
        values_[p] = *value;
      }
      Store();
    }
  }

  void ReadBinaryBody() {
    size_t vertex_size = 0;
    for (const Property& property : properties_) vertex_size += ScalarSize(property.type);
    const size_t available = content_.size() - offset_;
    if (num_vertices_ > available / vertex_size) {
      throw InputError(file_, 0,
                       "truncated: " + std::to_string(num_vertices_) + " vertices of " +
                           std::to_string(vertex_size) + " bytes need " +
                           std::to_string(num_vertices_ * vertex_size) +
                           " bytes after the header, found " + std::to_string(available));
    }
    const bool big_endian = *format_ == PlyFormat::kBinaryBigEndian;
    points_.xyz.reserve(num_vertices_);
    for (uint64_t i = 0; i < num_vertices_; ++i) {
      for (size_t p = 0; p < properties_.size(); ++p) {
        values_[p] = DecodeScalar(properties_[p].type, content_.data() + offset_, big_endian);
        offset_ += ScalarSize(properties_[p].type);
      }
      Store();
    }
  }

  const std::string content_;
  const std::string file_;
  size_t offset_ = 0;
  int64_t line_number_ = 0;

  std::optional<PlyFormat> format_;
  std::vector<Property> properties_;
  uint64_t num_vertices_ = 0;
  Section section_ = Section::kNone;
  bool seen_vertex_ = false;

  int source_[6] = {-1, -1, -1, -1, -1, -1};
  bool has_color_ = false;
  std::vector<double> values_;
  PlyPoints points_;
};

}  // namespace

PlyPoints ReadPly(const fs::path& path) {
  return PlyReader(path).Read();
}

}  // namespace viosfm

#include "viosfm/io/colmap_model.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "viosfm/io/binary_io.h"
#include "viosfm/io/colmap_convention.h"
#include "viosfm/io/rotation_checks.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace fs = std::filesystem;

namespace {

// Throws InputError describing where in which file the problem is.
using FailFn = std::function<void(const std::string& what)>;

[[noreturn]] void Throw(const FailFn& fail, const std::string& what) {
  fail(what);
  // `fail` always throws; this only satisfies [[noreturn]].
  throw InputError(what);
}

std::string SupportedModelNames() {
  std::string names;
  for (int id = 0; IsKnownCameraModelId(id); ++id) {
    if (!names.empty()) names += ", ";
    names += CameraModelName(static_cast<CameraModelId>(id));
  }
  return names;
}

// Unit quaternion from a file: within kFileRotationTolerance of unit
// (io/rotation_checks.h), as every reader; kept bit for bit when unit to
// rounding (as COLMAP writes them), normalised otherwise.
Eigen::Quaterniond QuaternionFromFile(double w, double x, double y, double z, const FailFn& fail) {
  Eigen::Quaterniond q(w, x, y, z);
  if (const std::string problem = CheckFileQuaternion(q); !problem.empty()) {
    Throw(fail, "expected a unit quaternion QW QX QY QZ: " + problem);
  }
  if (std::abs(q.squaredNorm() - 1.0) > 1e-12) q.normalize();
  return q;
}

// Image names are file names: non-empty, without control characters (a NUL
// ends a binary name, a line break a text line) and without spaces at either
// end (the text reader trims them), so that both formats hold every name.
std::string ImageNameProblem(const std::string& name) {
  if (name.empty()) return "expected an image name, found an empty one";
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      return "image name has a control character (byte " +
             std::to_string(static_cast<unsigned char>(c)) + ")";
    }
  }
  if (name.front() == ' ' || name.back() == ' ') {
    return "image name '" + name + "' starts or ends with a space";
  }
  return "";
}

// Builds a Reconstruction from records in file order and checks the
// references between them: images -> cameras, keypoints <-> tracks.
class ModelAssembler {
 public:
  void AddCamera(Camera camera, const FailFn& fail) {
    if (reconstruction_.ExistsCamera(camera.camera_id)) {
      Throw(fail, "duplicate camera id " + std::to_string(camera.camera_id));
    }
    // The readers check the parameter count before this.
    reconstruction_.AddCamera(CameraFromColmapConvention(std::move(camera)));
  }

  // `declared` are the keypoints' 3D point ids as the file states them;
  // `fail_keypoints` locates the image's keypoint data.
  void AddImage(Image image, std::vector<point3D_t> declared, const FailFn& fail,
                FailFn fail_keypoints) {
    if (const std::string problem = ImageNameProblem(image.name); !problem.empty()) {
      Throw(fail, "image " + std::to_string(image.image_id) + ": " + problem);
    }
    if (reconstruction_.ExistsImage(image.image_id)) {
      Throw(fail, "duplicate image id " + std::to_string(image.image_id));
    }
    if (!reconstruction_.ExistsCamera(image.camera_id)) {
      Throw(fail, "image " + std::to_string(image.image_id) + " refers to camera " +
                      std::to_string(image.camera_id) + ", which is not in the cameras file");
    }
    if (reconstruction_.ImageByName(image.name) != nullptr) {
      Throw(fail, "duplicate image name '" + image.name + "'");
    }
    image.registered = true;
    image.timestamp_ns = TimestampFromImageName(image.name);
    declared_.emplace(image.image_id, Declared{std::move(declared), std::move(fail_keypoints)});
    reconstruction_.AddImage(std::move(image));
  }

  void AddPoint3D(point3D_t point3D_id, Point3D point3D, const FailFn& fail) {
    const std::string point_name = "3D point " + std::to_string(point3D_id);
    if (point3D_id == kInvalidPoint3DId) Throw(fail, "invalid 3D point id");
    if (reconstruction_.ExistsPoint3D(point3D_id)) Throw(fail, "duplicate " + point_name);
    for (size_t i = 0; i < point3D.track.size(); ++i) {
      const TrackElement& element = point3D.track[i];
      const std::string element_name = "track element (" + std::to_string(element.image_id) + ", " +
                                       std::to_string(element.point2D_idx) + ")";
      if (!reconstruction_.ExistsImage(element.image_id)) {
        Throw(fail, point_name + ": " + element_name + " refers to image " +
                        std::to_string(element.image_id) + ", which is not in the images file");
      }
      const std::vector<point3D_t>& declared = declared_.at(element.image_id).ids;
      if (element.point2D_idx >= declared.size()) {
        Throw(fail, point_name + ": " + element_name + " refers to keypoint " +
                        std::to_string(element.point2D_idx) + ", but the image has " +
                        std::to_string(declared.size()) + " keypoints");
      }
      if (declared[element.point2D_idx] != point3D_id) {
        Throw(fail, point_name + ": " + element_name +
                        " disagrees with the images file, where that keypoint observes " +
                        (declared[element.point2D_idx] == kInvalidPoint3DId
                             ? std::string("no 3D point")
                             : "3D point " + std::to_string(declared[element.point2D_idx])));
      }
      for (size_t j = 0; j < i; ++j) {
        if (point3D.track[j] == element) Throw(fail, point_name + ": duplicate " + element_name);
      }
    }
    reconstruction_.AddPoint3DWithId(point3D_id, std::move(point3D));
  }

  Reconstruction Finish() {
    for (const image_t image_id : reconstruction_.ImageIds()) {
      const Image& image = reconstruction_.GetImage(image_id);
      const Declared& declared = declared_.at(image_id);
      for (size_t idx = 0; idx < declared.ids.size(); ++idx) {
        const point3D_t point3D_id = declared.ids[idx];
        if (point3D_id == kInvalidPoint3DId || image.points2D[idx].point3D_id == point3D_id) {
          continue;
        }
        Throw(declared.fail, "image " + std::to_string(image_id) + ": keypoint " +
                                 std::to_string(idx) + " observes 3D point " +
                                 std::to_string(point3D_id) +
                                 (reconstruction_.ExistsPoint3D(point3D_id)
                                      ? ", whose track in the points3D file does not list it"
                                      : ", which is not in the points3D file"));
      }
    }
    return std::move(reconstruction_);
  }

 private:
  struct Declared {
    std::vector<point3D_t> ids;
    FailFn fail;
  };
  Reconstruction reconstruction_;
  std::unordered_map<image_t, Declared> declared_;
};

// ---------------------------------------------------------------- text ----

template <typename T>
T ParseUnsignedField(std::string_view token, const FailFn& fail, const std::string& what) {
  uint64_t value = 0;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (token.empty() || ec != std::errc() || ptr != end ||
      value > static_cast<uint64_t>(std::numeric_limits<T>::max())) {
    Throw(fail, "expected " + what + " (an integer in [0, " +
                    std::to_string(std::numeric_limits<T>::max()) + "]), found '" +
                    std::string(token) + "'");
  }
  return static_cast<T>(value);
}

double ParseDoubleField(std::string_view token, const FailFn& fail, const std::string& what) {
  const std::optional<double> value = ParseDouble(token);
  if (!value || !std::isfinite(*value)) {
    Throw(fail, "expected " + what + " (a finite number), found '" + std::string(token) + "'");
  }
  return *value;
}

struct TextLine {
  std::string_view text;  // without the line break
  int64_t number = 0;     // 1-based
};

std::vector<TextLine> SplitLines(const std::string& content) {
  std::vector<TextLine> lines;
  size_t start = 0;
  int64_t number = 1;
  while (start < content.size()) {
    size_t end = content.find('\n', start);
    if (end == std::string::npos) end = content.size();
    std::string_view text(content.data() + start, end - start);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    lines.push_back({text, number++});
    start = end + 1;
  }
  return lines;
}

bool IsDataLine(std::string_view text) {
  const std::string_view trimmed = Trim(text);
  return !trimmed.empty() && trimmed.front() != '#';
}

FailFn TextFail(const std::string& path, int64_t line) {
  return [path, line](const std::string& what) { throw InputError(path, line, what); };
}

std::vector<std::string_view> Tokens(std::string_view text) {
  return Split(Trim(text), " \t", /*skip_empty=*/true);
}

void ReadCamerasText(const fs::path& path, ModelAssembler* assembler) {
  const std::string content = ReadTextFile(path);
  for (const TextLine& line : SplitLines(content)) {
    if (!IsDataLine(line.text)) continue;
    const FailFn fail = TextFail(path.string(), line.number);
    const std::vector<std::string_view> tokens = Tokens(line.text);
    if (tokens.size() < 4) {
      Throw(fail, "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[], found " +
                      std::to_string(tokens.size()) + " fields");
    }
    Camera camera;
    camera.camera_id = ParseUnsignedField<camera_t>(tokens[0], fail, "CAMERA_ID");
    if (camera.camera_id == kInvalidCameraId) Throw(fail, "invalid CAMERA_ID");
    camera.model_id = CameraModelIdFromName(std::string(tokens[1]));
    if (camera.model_id == CameraModelId::kInvalid) {
      Throw(fail, "unknown camera model '" + std::string(tokens[1]) + "' (expected one of " +
                      SupportedModelNames() + ")");
    }
    camera.width = ParseUnsignedField<uint64_t>(tokens[2], fail, "WIDTH");
    camera.height = ParseUnsignedField<uint64_t>(tokens[3], fail, "HEIGHT");
    const size_t num_params = static_cast<size_t>(CameraModelNumParams(camera.model_id));
    if (tokens.size() - 4 != num_params) {
      Throw(fail, "camera model " + camera.ModelName() + " expects " + std::to_string(num_params) +
                      " parameters, found " + std::to_string(tokens.size() - 4));
    }
    for (size_t i = 4; i < tokens.size(); ++i) {
      camera.params.push_back(ParseDoubleField(tokens[i], fail, "a camera parameter"));
    }
    assembler->AddCamera(std::move(camera), fail);
  }
}

void ReadImagesText(const fs::path& path, ModelAssembler* assembler) {
  const std::string content = ReadTextFile(path);
  const std::vector<TextLine> lines = SplitLines(content);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (!IsDataLine(lines[i].text)) continue;
    const TextLine& line = lines[i];
    const FailFn fail = TextFail(path.string(), line.number);
    const std::vector<std::string_view> tokens = Tokens(line.text);
    if (tokens.size() < 10) {
      Throw(fail, "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, found " +
                      std::to_string(tokens.size()) + " fields");
    }
    Image image;
    image.image_id = ParseUnsignedField<image_t>(tokens[0], fail, "IMAGE_ID");
    if (image.image_id == kInvalidImageId) Throw(fail, "invalid IMAGE_ID");
    const char* kPoseNames[7] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    double pose[7];
    for (int k = 0; k < 7; ++k) pose[k] = ParseDoubleField(tokens[1 + k], fail, kPoseNames[k]);
    image.cam_from_world.rotation = QuaternionFromFile(pose[0], pose[1], pose[2], pose[3], fail);
    image.cam_from_world.translation = Eigen::Vector3d(pose[4], pose[5], pose[6]);
    image.camera_id = ParseUnsignedField<camera_t>(tokens[8], fail, "CAMERA_ID");
    // The name is the rest of the line (it may contain spaces).
    const std::string_view trimmed = Trim(line.text);
    image.name = std::string(Trim(trimmed.substr(tokens[9].data() - trimmed.data())));

    // The keypoint line follows directly; it is empty for no keypoints.
    if (i + 1 >= lines.size()) {
      Throw(fail, "expected a second line with the keypoints (X Y POINT3D_ID ...) of image " +
                      std::to_string(image.image_id) + ", found the end of the file");
    }
    const TextLine& points_line = lines[++i];
    const FailFn fail_points = TextFail(path.string(), points_line.number);
    const std::vector<std::string_view> values = Tokens(points_line.text);
    if (values.size() % 3 != 0) {
      Throw(fail_points, "expected keypoints as triples X Y POINT3D_ID, found " +
                             std::to_string(values.size()) + " fields");
    }
    std::vector<point3D_t> declared;
    declared.reserve(values.size() / 3);
    image.points2D.resize(values.size() / 3);
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      image.points2D[k].xy.x() =
          ParseDoubleField(values[3 * k], fail_points, "X") - kColmapPixelOffset;
      image.points2D[k].xy.y() =
          ParseDoubleField(values[3 * k + 1], fail_points, "Y") - kColmapPixelOffset;
      const std::string_view id = values[3 * k + 2];
      declared.push_back(id == "-1"
                             ? kInvalidPoint3DId
                             : ParseUnsignedField<point3D_t>(id, fail_points, "POINT3D_ID or -1"));
    }
    assembler->AddImage(std::move(image), std::move(declared), fail, fail_points);
  }
}

void ReadPoints3DText(const fs::path& path, ModelAssembler* assembler) {
  const std::string content = ReadTextFile(path);
  for (const TextLine& line : SplitLines(content)) {
    if (!IsDataLine(line.text)) continue;
    const FailFn fail = TextFail(path.string(), line.number);
    const std::vector<std::string_view> tokens = Tokens(line.text);
    if (tokens.size() < 8 || (tokens.size() - 8) % 2 != 0) {
      Throw(fail, "expected POINT3D_ID X Y Z R G B ERROR and pairs IMAGE_ID POINT2D_IDX, found " +
                      std::to_string(tokens.size()) + " fields");
    }
    const point3D_t point3D_id = ParseUnsignedField<point3D_t>(tokens[0], fail, "POINT3D_ID");
    Point3D point3D;
    point3D.xyz = Eigen::Vector3d(ParseDoubleField(tokens[1], fail, "X"),
                                  ParseDoubleField(tokens[2], fail, "Y"),
                                  ParseDoubleField(tokens[3], fail, "Z"));
    for (int c = 0; c < 3; ++c) {
      point3D.color[c] = ParseUnsignedField<uint8_t>(tokens[4 + c], fail, "a colour R G B");
    }
    point3D.error = ParseDoubleField(tokens[7], fail, "ERROR");
    for (size_t k = 8; k < tokens.size(); k += 2) {
      point3D.track.push_back({ParseUnsignedField<image_t>(tokens[k], fail, "IMAGE_ID"),
                               ParseUnsignedField<point2D_t>(tokens[k + 1], fail, "POINT2D_IDX")});
    }
    assembler->AddPoint3D(point3D_id, std::move(point3D), fail);
  }
}

// -------------------------------------------------------------- binary ----

// A FailFn that throws at the reader's current position.
FailFn FailerAt(const LittleEndianReader& reader) {
  return [path = reader.path(), prefix = reader.Describe("")](const std::string& what) {
    throw InputError(path, 0, prefix + what);
  };
}

// A double that must be finite (COLMAP never writes NaN or infinity; a model
// holding them is corrupt, and they would not survive a text round trip).
double ReadFinite(LittleEndianReader& reader, const std::string& what) {
  const double value = reader.Read<double>(what);
  if (!std::isfinite(value)) {
    reader.Fail("expected a finite number as " + what + ", found " + std::to_string(value));
  }
  return value;
}

std::string RecordName(const char* kind, uint64_t index, uint64_t count) {
  return std::string(kind) + " record " + std::to_string(index + 1) + " of " +
         std::to_string(count);
}

void ReadCamerasBinary(const fs::path& path, ModelAssembler* assembler) {
  LittleEndianReader reader(path);
  const uint64_t count = reader.Read<uint64_t>("the number of cameras (uint64)");
  reader.RequireCount(count, 24, "cameras");
  for (uint64_t i = 0; i < count; ++i) {
    reader.SetRecord(RecordName("camera", i, count));
    const FailFn fail = FailerAt(reader);
    Camera camera;
    camera.camera_id = reader.Read<camera_t>("the camera id (uint32)");
    const int32_t model = reader.Read<int32_t>("the camera model id (int32)");
    if (!IsKnownCameraModelId(model)) {
      reader.Fail("unknown camera model id " + std::to_string(model) + " (expected 0 to 10)");
    }
    camera.model_id = static_cast<CameraModelId>(model);
    camera.width = reader.Read<uint64_t>("the width (uint64)");
    camera.height = reader.Read<uint64_t>("the height (uint64)");
    const int num_params = CameraModelNumParams(camera.model_id);
    for (int k = 0; k < num_params; ++k) {
      camera.params.push_back(ReadFinite(reader, "parameter " + std::to_string(k + 1) + " of " +
                                                     std::to_string(num_params) + " of a " +
                                                     camera.ModelName() + " camera (double)"));
    }
    assembler->AddCamera(std::move(camera), fail);
  }
  reader.ExpectEnd();
}

void ReadImagesBinary(const fs::path& path, ModelAssembler* assembler) {
  LittleEndianReader reader(path);
  const uint64_t count = reader.Read<uint64_t>("the number of images (uint64)");
  reader.RequireCount(count, 4 + 7 * 8 + 4 + 1 + 8, "images");
  for (uint64_t i = 0; i < count; ++i) {
    reader.SetRecord(RecordName("image", i, count));
    const FailFn fail = FailerAt(reader);
    Image image;
    image.image_id = reader.Read<image_t>("the image id (uint32)");
    double pose[7];
    const char* kPoseNames[7] = {"qw", "qx", "qy", "qz", "tx", "ty", "tz"};
    for (int k = 0; k < 7; ++k)
      pose[k] = ReadFinite(reader, std::string(kPoseNames[k]) + " (double)");
    image.cam_from_world.rotation = QuaternionFromFile(pose[0], pose[1], pose[2], pose[3], fail);
    image.cam_from_world.translation = Eigen::Vector3d(pose[4], pose[5], pose[6]);
    image.camera_id = reader.Read<camera_t>("the camera id (uint32)");
    image.name = reader.ReadNullTerminated("the image name");
    reader.SetRecord(RecordName("image", i, count) + ", id " + std::to_string(image.image_id) +
                     " '" + image.name + "'");
    const FailFn fail_points = FailerAt(reader);
    const uint64_t num_points2D = reader.Read<uint64_t>("the number of keypoints (uint64)");
    reader.RequireCount(num_points2D, 24, "keypoints");
    image.points2D.resize(num_points2D);
    std::vector<point3D_t> declared(num_points2D);
    for (uint64_t k = 0; k < num_points2D; ++k) {
      image.points2D[k].xy.x() = ReadFinite(reader, "keypoint x (double)") - kColmapPixelOffset;
      image.points2D[k].xy.y() = ReadFinite(reader, "keypoint y (double)") - kColmapPixelOffset;
      declared[k] = reader.Read<point3D_t>("keypoint 3D point id (uint64)");
    }
    assembler->AddImage(std::move(image), std::move(declared), fail, fail_points);
  }
  reader.ExpectEnd();
}

void ReadPoints3DBinary(const fs::path& path, ModelAssembler* assembler) {
  LittleEndianReader reader(path);
  const uint64_t count = reader.Read<uint64_t>("the number of 3D points (uint64)");
  reader.RequireCount(count, 8 + 3 * 8 + 3 + 8 + 8, "3D points");
  for (uint64_t i = 0; i < count; ++i) {
    reader.SetRecord(RecordName("3D point", i, count));
    const FailFn fail = FailerAt(reader);
    const point3D_t point3D_id = reader.Read<point3D_t>("the 3D point id (uint64)");
    Point3D point3D;
    for (int k = 0; k < 3; ++k) point3D.xyz[k] = ReadFinite(reader, "a coordinate (double)");
    for (int k = 0; k < 3; ++k) point3D.color[k] = reader.Read<uint8_t>("a colour (uint8)");
    point3D.error = ReadFinite(reader, "the error (double)");
    const uint64_t track_length = reader.Read<uint64_t>("the track length (uint64)");
    reader.RequireCount(track_length, 8, "track elements");
    point3D.track.resize(track_length);
    for (TrackElement& element : point3D.track) {
      element.image_id = reader.Read<image_t>("a track image id (uint32)");
      element.point2D_idx = reader.Read<point2D_t>("a track keypoint index (uint32)");
    }
    assembler->AddPoint3D(point3D_id, std::move(point3D), fail);
  }
  reader.ExpectEnd();
}

// ------------------------------------------------------------- writing ----

// Text numbers as COLMAP prints them: an ostream with precision 17 ("%.17g").
std::ostringstream MakeTextStream() {
  std::ostringstream stream;
  stream.precision(17);
  return stream;
}

void WriteCamerasText(const fs::path& path, const Reconstruction& reconstruction) {
  std::ostringstream out = MakeTextStream();
  out << "# Camera list with one line of data per camera:\n"
      << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      << "# Number of cameras: " << reconstruction.NumCameras() << "\n";
  for (const camera_t camera_id : reconstruction.CameraIds()) {
    VIOSFM_CHECK(reconstruction.GetCamera(camera_id).HasValidParams()) << "camera " << camera_id;
    const Camera camera = CameraToColmapConvention(reconstruction.GetCamera(camera_id));
    out << camera_id << ' ' << camera.ModelName() << ' ' << camera.width << ' ' << camera.height;
    for (const double param : camera.params) out << ' ' << param;
    out << '\n';
  }
  const std::string text = out.str();
  WriteFileAtomically(path, [&](std::ostream& stream) { stream << text; });
}

void WriteImagesText(const fs::path& path, const Reconstruction& reconstruction) {
  const std::vector<image_t> image_ids = reconstruction.RegImageIds();
  std::ostringstream out = MakeTextStream();
  out << "# Image list with two lines of data per image:\n"
      << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      << "# Number of images: " << image_ids.size()
      << ", mean observations per image: " << reconstruction.ComputeMeanObservationsPerRegImage()
      << "\n";
  for (const image_t image_id : image_ids) {
    const Image& image = reconstruction.GetImage(image_id);
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    out << image_id << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << t.x()
        << ' ' << t.y() << ' ' << t.z() << ' ' << image.camera_id << ' ' << image.name << '\n';
    bool first = true;
    for (const Point2D& point2D : image.points2D) {
      if (!first) out << ' ';
      first = false;
      out << point2D.xy.x() + kColmapPixelOffset << ' ' << point2D.xy.y() + kColmapPixelOffset
          << ' ';
      if (point2D.HasPoint3D()) {
        out << point2D.point3D_id;
      } else {
        out << "-1";
      }
    }
    out << '\n';
  }
  const std::string text = out.str();
  WriteFileAtomically(path, [&](std::ostream& stream) { stream << text; });
}

void WritePoints3DText(const fs::path& path, const Reconstruction& reconstruction) {
  std::ostringstream out = MakeTextStream();
  out << "# 3D point list with one line of data per point:\n"
      << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      << "# Number of points: " << reconstruction.NumPoints3D()
      << ", mean track length: " << reconstruction.ComputeMeanTrackLength() << "\n";
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    out << point3D_id << ' ' << point3D.xyz.x() << ' ' << point3D.xyz.y() << ' ' << point3D.xyz.z()
        << ' ' << static_cast<int>(point3D.color[0]) << ' ' << static_cast<int>(point3D.color[1])
        << ' ' << static_cast<int>(point3D.color[2]) << ' ' << point3D.error;
    // COLMAP writes "ERROR " and then the track without its trailing space,
    // so a point without a track keeps a trailing space.
    if (point3D.track.empty()) out << ' ';
    for (const TrackElement& element : point3D.track) {
      out << ' ' << element.image_id << ' ' << element.point2D_idx;
    }
    out << '\n';
  }
  const std::string text = out.str();
  WriteFileAtomically(path, [&](std::ostream& stream) { stream << text; });
}

void WriteCamerasBinary(const fs::path& path, const Reconstruction& reconstruction) {
  LittleEndianWriter out;
  out.Write<uint64_t>(reconstruction.NumCameras());
  for (const camera_t camera_id : reconstruction.CameraIds()) {
    VIOSFM_CHECK(reconstruction.GetCamera(camera_id).HasValidParams()) << "camera " << camera_id;
    const Camera camera = CameraToColmapConvention(reconstruction.GetCamera(camera_id));
    out.Write<camera_t>(camera_id);
    out.Write<int32_t>(static_cast<int32_t>(camera.model_id));
    out.Write<uint64_t>(camera.width);
    out.Write<uint64_t>(camera.height);
    for (const double param : camera.params) out.Write<double>(param);
  }
  out.SaveTo(path);
}

void WriteImagesBinary(const fs::path& path, const Reconstruction& reconstruction) {
  const std::vector<image_t> image_ids = reconstruction.RegImageIds();
  LittleEndianWriter out;
  out.Write<uint64_t>(image_ids.size());
  for (const image_t image_id : image_ids) {
    const Image& image = reconstruction.GetImage(image_id);
    VIOSFM_CHECK(image.name.find('\0') == std::string::npos) << "image name with a NUL";
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    out.Write<image_t>(image_id);
    for (const double value : {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()}) {
      out.Write<double>(value);
    }
    out.Write<camera_t>(image.camera_id);
    out.WriteNullTerminated(image.name);
    out.Write<uint64_t>(image.points2D.size());
    for (const Point2D& point2D : image.points2D) {
      out.Write<double>(point2D.xy.x() + kColmapPixelOffset);
      out.Write<double>(point2D.xy.y() + kColmapPixelOffset);
      out.Write<point3D_t>(point2D.point3D_id);
    }
  }
  out.SaveTo(path);
}

void WritePoints3DBinary(const fs::path& path, const Reconstruction& reconstruction) {
  LittleEndianWriter out;
  out.Write<uint64_t>(reconstruction.NumPoints3D());
  for (const point3D_t point3D_id : reconstruction.Point3DIds()) {
    const Point3D& point3D = reconstruction.GetPoint3D(point3D_id);
    out.Write<point3D_t>(point3D_id);
    for (int k = 0; k < 3; ++k) out.Write<double>(point3D.xyz[k]);
    for (int k = 0; k < 3; ++k) out.Write<uint8_t>(point3D.color[k]);
    out.Write<double>(point3D.error);
    out.Write<uint64_t>(point3D.track.size());
    for (const TrackElement& element : point3D.track) {
      out.Write<image_t>(element.image_id);
      out.Write<point2D_t>(element.point2D_idx);
    }
  }
  out.SaveTo(path);
}

// Iteration order of a std::unordered_map after inserting `ids` in order.
template <typename Id>
std::vector<Id> UnorderedMapOrder(const std::vector<Id>& ids) {
  std::unordered_map<Id, char> map;
  for (const Id id : ids) map.emplace(id, 0);
  std::vector<Id> order;
  order.reserve(map.size());
  for (const auto& entry : map) order.push_back(entry.first);
  return order;
}

}  // namespace

Reconstruction ReadColmapModelText(const fs::path& folder) {
  RequireFolder(folder, "COLMAP model folder");
  ModelAssembler assembler;
  ReadCamerasText(folder / "cameras.txt", &assembler);
  ReadImagesText(folder / "images.txt", &assembler);
  ReadPoints3DText(folder / "points3D.txt", &assembler);
  return assembler.Finish();
}

Reconstruction ReadColmapModelBinary(const fs::path& folder) {
  RequireFolder(folder, "COLMAP model folder");
  ModelAssembler assembler;
  ReadCamerasBinary(folder / "cameras.bin", &assembler);
  ReadImagesBinary(folder / "images.bin", &assembler);
  ReadPoints3DBinary(folder / "points3D.bin", &assembler);
  return assembler.Finish();
}

Reconstruction ReadColmapModel(const fs::path& folder) {
  RequireFolder(folder, "COLMAP model folder");
  if (fs::exists(folder / "cameras.bin")) return ReadColmapModelBinary(folder);
  return ReadColmapModelText(folder);
}

void WriteColmapModelText(const fs::path& folder, const Reconstruction& reconstruction) {
  fs::create_directories(folder);
  WriteCamerasText(folder / "cameras.txt", reconstruction);
  WriteImagesText(folder / "images.txt", reconstruction);
  WritePoints3DText(folder / "points3D.txt", reconstruction);
}

void WriteColmapModelBinary(const fs::path& folder, const Reconstruction& reconstruction) {
  fs::create_directories(folder);
  WriteCamerasBinary(folder / "cameras.bin", reconstruction);
  WriteImagesBinary(folder / "images.bin", reconstruction);
  WritePoints3DBinary(folder / "points3D.bin", reconstruction);
}

void WriteColmapModel(const fs::path& folder, const Reconstruction& reconstruction,
                      ColmapModelFormat format) {
  if (format == ColmapModelFormat::kText) {
    WriteColmapModelText(folder, reconstruction);
  } else {
    WriteColmapModelBinary(folder, reconstruction);
  }
}

void WriteColmapModelFolder(const fs::path& folder, const Reconstruction& reconstruction,
                            ColmapModelFormat format) {
  WriteFolderAtomically(
      folder, [&](const fs::path& tmp) { WriteColmapModel(tmp, reconstruction, format); });
}

void ReorderAsColmapAfterRead(Reconstruction* reconstruction) {
  VIOSFM_CHECK(reconstruction != nullptr);
  reconstruction->ReorderCameras(UnorderedMapOrder(reconstruction->CameraIds()));
  // Only registered images are in the files COLMAP reads; others go last.
  std::vector<image_t> image_ids = UnorderedMapOrder(reconstruction->RegImageIds());
  for (const image_t image_id : reconstruction->ImageIds()) {
    if (!reconstruction->GetImage(image_id).registered) image_ids.push_back(image_id);
  }
  reconstruction->ReorderImages(image_ids);
  reconstruction->ReorderPoints3D(UnorderedMapOrder(reconstruction->Point3DIds()));
}

}  // namespace viosfm

#include "viosfm/io/transforms_json.h"

#include <Eigen/SVD>
#include <cmath>
#include <nlohmann/json.hpp>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

// OpenCV camera axes -> OpenGL camera axes: flip y and z.
const Eigen::Matrix3d kFlipYZ = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();

// COLMAP/nerfstudio put the top-left image corner at (0, 0); viosfm puts the
// centre of the top-left pixel there.
constexpr double kPixelShift = 0.5;

}  // namespace

void WriteTransformsJson(const fs::path& path, const TransformsJson& transforms) {
  const Camera& camera = transforms.camera;
  if (!camera.HasValidParams()) {
    throw InputError(path.string(), 0, "camera " + camera.ModelName() + " has invalid parameters");
  }
  const std::vector<double>& p = camera.params;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::string model;
  std::vector<std::pair<std::string, double>> distortion;
  switch (camera.model_id) {
    case CameraModelId::kSimplePinhole:
      fx = fy = p[0], cx = p[1], cy = p[2], model = "PINHOLE";
      break;
    case CameraModelId::kPinhole:
      fx = p[0], fy = p[1], cx = p[2], cy = p[3], model = "PINHOLE";
      break;
    case CameraModelId::kSimpleRadial:
      fx = fy = p[0], cx = p[1], cy = p[2], model = "OPENCV";
      distortion = {{"k1", p[3]}, {"k2", 0.0}, {"p1", 0.0}, {"p2", 0.0}};
      break;
    case CameraModelId::kRadial:
      fx = fy = p[0], cx = p[1], cy = p[2], model = "OPENCV";
      distortion = {{"k1", p[3]}, {"k2", p[4]}, {"p1", 0.0}, {"p2", 0.0}};
      break;
    case CameraModelId::kOpenCV:
      fx = p[0], fy = p[1], cx = p[2], cy = p[3], model = "OPENCV";
      distortion = {{"k1", p[4]}, {"k2", p[5]}, {"p1", p[6]}, {"p2", p[7]}};
      break;
    case CameraModelId::kOpenCVFisheye:
      fx = p[0], fy = p[1], cx = p[2], cy = p[3], model = "OPENCV_FISHEYE";
      distortion = {{"k1", p[4]}, {"k2", p[5]}, {"k3", p[6]}, {"k4", p[7]}};
      break;
    default:
      throw InputError(path.string(), 0,
                       "camera model " + camera.ModelName() +
                           " has no transforms.json equivalent (PINHOLE, OPENCV, OPENCV_FISHEYE)");
  }
  json document;
  document["camera_model"] = model;
  document["fl_x"] = fx;
  document["fl_y"] = fy;
  document["cx"] = cx + kPixelShift;
  document["cy"] = cy + kPixelShift;
  document["w"] = camera.width;
  document["h"] = camera.height;
  for (const auto& [name, value] : distortion) document[name] = value;
  if (!transforms.ply_file_path.empty()) document["ply_file_path"] = transforms.ply_file_path;
  json frames = json::array();
  for (const TransformsFrame& frame : transforms.frames) {
    const Rigid3d world_from_cam = frame.cam_from_world.Inverse();
    const Eigen::Matrix3d rotation = world_from_cam.rotation.toRotationMatrix() * kFlipYZ;
    json matrix = json::array();
    for (int r = 0; r < 4; ++r) {
      json row = json::array();
      for (int c = 0; c < 4; ++c) {
        if (r == 3) {
          row.push_back(c == 3 ? 1.0 : 0.0);
        } else {
          row.push_back(c < 3 ? rotation(r, c) : world_from_cam.translation[r]);
        }
      }
      matrix.push_back(row);
    }
    frames.push_back({{"file_path", frame.file_path}, {"transform_matrix", matrix}});
  }
  document["frames"] = frames;
  const std::string text = document.dump(2);  // doubles with 17 significant digits
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text << "\n"; });
}

TransformsJson ReadTransformsJson(const fs::path& path) {
  const std::string p = path.string();
  json document;
  try {
    document = json::parse(ReadTextFile(path));
  } catch (const json::parse_error& e) {
    throw InputError(p, 0, std::string("not valid JSON: ") + e.what());
  }
  const auto number = [&](const json& object, const std::string& key, const std::string& where) {
    if (!object.contains(key) || !object[key].is_number()) {
      throw InputError(p, 0, where + "expected a number \"" + key + "\"");
    }
    return object[key].get<double>();
  };
  if (!document.is_object()) throw InputError(p, 0, "expected a JSON object");
  const std::string model =
      document.contains("camera_model") && document["camera_model"].is_string()
          ? document["camera_model"].get<std::string>()
          : "OPENCV";
  TransformsJson transforms;
  const double fx = number(document, "fl_x", "");
  const double fy = number(document, "fl_y", "");
  const double cx = number(document, "cx", "") - kPixelShift;
  const double cy = number(document, "cy", "") - kPixelShift;
  const double w = number(document, "w", "");
  const double h = number(document, "h", "");
  const auto optional = [&](const std::string& key) {
    return document.contains(key) ? number(document, key, "") : 0.0;
  };
  if (model == "PINHOLE") {
    transforms.camera = MakeCamera(CameraModelId::kPinhole, static_cast<uint64_t>(w),
                                   static_cast<uint64_t>(h), {fx, fy, cx, cy});
  } else if (model == "OPENCV") {
    transforms.camera = MakeCamera(
        CameraModelId::kOpenCV, static_cast<uint64_t>(w), static_cast<uint64_t>(h),
        {fx, fy, cx, cy, optional("k1"), optional("k2"), optional("p1"), optional("p2")});
  } else if (model == "OPENCV_FISHEYE") {
    transforms.camera = MakeCamera(
        CameraModelId::kOpenCVFisheye, static_cast<uint64_t>(w), static_cast<uint64_t>(h),
        {fx, fy, cx, cy, optional("k1"), optional("k2"), optional("k3"), optional("k4")});
  } else {
    throw InputError(p, 0,
                     "camera_model \"" + model + "\" (expected PINHOLE, OPENCV or OPENCV_FISHEYE)");
  }
  if (document.contains("ply_file_path") && document["ply_file_path"].is_string()) {
    transforms.ply_file_path = document["ply_file_path"].get<std::string>();
  }
  if (!document.contains("frames") || !document["frames"].is_array()) {
    throw InputError(p, 0, "expected an array \"frames\"");
  }
  const json& frames = document["frames"];
  for (size_t i = 0; i < frames.size(); ++i) {
    const json& frame = frames[i];
    const std::string where = "frame " + std::to_string(i) + ": ";
    if (!frame.is_object() || !frame.contains("file_path") || !frame["file_path"].is_string()) {
      throw InputError(p, 0, where + "expected a string \"file_path\"");
    }
    const json& matrix = frame.contains("transform_matrix") ? frame["transform_matrix"] : json();
    if (!matrix.is_array() || matrix.size() != 4) {
      throw InputError(p, 0, where + "expected \"transform_matrix\" as 4 rows of 4 numbers");
    }
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      if (!matrix[r].is_array() || matrix[r].size() != 4) {
        throw InputError(p, 0, where + "expected \"transform_matrix\" as 4 rows of 4 numbers");
      }
      for (int c = 0; c < 4; ++c) {
        if (!matrix[r][c].is_number()) {
          throw InputError(p, 0, where + "transform_matrix holds a value that is not a number");
        }
        m(r, c) = matrix[r][c].get<double>();
      }
    }
    const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>() * kFlipYZ;
    if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-12 ||
        (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
        rotation.determinant() < 0) {
      throw InputError(p, 0, where + "transform_matrix is not a rigid camera-to-world transform");
    }
    const Rigid3d world_from_cam(Eigen::Quaterniond(rotation).normalized(),
                                 Eigen::Vector3d(m.topRightCorner<3, 1>()));
    transforms.frames.push_back({frame["file_path"].get<std::string>(), world_from_cam.Inverse()});
  }
  return transforms;
}

}  // namespace viosfm

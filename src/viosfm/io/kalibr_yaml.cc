#include "viosfm/io/kalibr_yaml.h"

#include <cmath>
#include <vector>

#include "viosfm/io/dataset_checks.h"
#include "viosfm/io/rotation_checks.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

constexpr char kSupportedDistortionModels[] =
    "radial-tangential (or radtan), equidistant (or equi), none";

}  // namespace

Camera ReadKalibrCameraIntrinsics(const YamlMap& yaml, const std::string& coefficients_key) {
  Camera camera;
  if (yaml.Has("camera_model")) {
    const std::string model = yaml.GetString("camera_model");
    if (ToLower(model) != "pinhole") {
      yaml.Fail("camera_model", "unknown camera model '" + model + "'; supported: pinhole");
    }
  }
  const std::vector<double> resolution = yaml.GetDoubles("resolution", 2);
  for (double value : resolution) {
    if (value < 1.0 || value != std::floor(value) || value > 1e6) {
      yaml.Fail("resolution", "expected [width, height] as positive integers (pixels)");
    }
  }
  camera.width = static_cast<uint64_t>(resolution[0]);
  camera.height = static_cast<uint64_t>(resolution[1]);
  const std::vector<double> intrinsics = yaml.GetDoubles("intrinsics", 4);
  if (intrinsics[0] <= 0.0 || intrinsics[1] <= 0.0) {
    yaml.Fail("intrinsics", "expected [fu, fv, cu, cv] with positive focal lengths");
  }

  std::string distortion = "none";
  if (yaml.Has("distortion_model")) distortion = ToLower(yaml.GetString("distortion_model"));
  std::vector<double> coefficients;
  if (yaml.Has(coefficients_key)) {
    coefficients = yaml.GetDoubles(coefficients_key);
  }
  const auto require_coefficients = [&](size_t count, const std::string& names) {
    if (coefficients.size() != count) {
      yaml.Fail(coefficients_key, "distortion_model '" + distortion + "' expects " +
                                      std::to_string(count) + " coefficients (" + names +
                                      "), got " + std::to_string(coefficients.size()));
    }
  };
  camera.params = intrinsics;
  if (distortion == "radial-tangential" || distortion == "radtan") {
    require_coefficients(4, "k1, k2, p1, p2");
    camera.model_id = CameraModelId::kOpenCV;
    camera.params.insert(camera.params.end(), coefficients.begin(), coefficients.end());
  } else if (distortion == "equidistant" || distortion == "equi") {
    require_coefficients(4, "k1, k2, k3, k4");
    camera.model_id = CameraModelId::kOpenCVFisheye;
    camera.params.insert(camera.params.end(), coefficients.begin(), coefficients.end());
  } else if (distortion == "none") {
    for (double value : coefficients) {
      if (value != 0.0) {
        yaml.Fail(coefficients_key,
                  "distortion_model 'none' expects no (or only zero) coefficients");
      }
    }
    camera.model_id = CameraModelId::kPinhole;
  } else {
    yaml.Fail("distortion_model", "unknown distortion model '" + distortion +
                                      "'; supported: " + kSupportedDistortionModels);
  }
  VIOSFM_CHECK(camera.HasValidParams());
  if (const std::string problem = CheckCameraCalibration(camera); !problem.empty()) {
    const bool distortion = problem.find("distortion") != std::string::npos;
    yaml.Fail(distortion ? coefficients_key : "intrinsics",
              "expected a calibration a camera can have: " + problem);
  }
  return camera;
}

Rigid3d ReadRigidTransform(const YamlMap& yaml, const std::string& key) {
  const Eigen::Matrix4d matrix = yaml.GetMatrix4(key);
  if ((matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    yaml.Fail(key, "expected a homogeneous transform whose last row is 0 0 0 1");
  }
  if (const std::string problem = CheckFileRotationMatrix(matrix.topLeftCorner<3, 3>());
      !problem.empty()) {
    yaml.Fail(key, "expected the top-left 3x3 block to be a rotation matrix: " + problem);
  }
  const Rigid3d transform = Rigid3d::FromMatrix(matrix.topRows<3>());
  // |t| is the same for a transform and its inverse (T_BS, T_cam_imu).
  if (const std::string problem = CheckRigTranslation(transform); !problem.empty()) {
    yaml.Fail(key, "expected a sensor's place on the rig: " + problem);
  }
  return transform;
}

}  // namespace viosfm

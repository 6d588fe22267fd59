#include "viosfm/sensor/sensor_rig.h"

#include <cmath>
#include <sstream>

#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

std::string ValidateCamera(const Camera& camera) {
  std::ostringstream message;
  if (!IsCameraModelSupported(camera.model_id)) {
    return "camera: " + UnsupportedCameraModelMessage(camera.model_id);
  }
  if (!camera.HasValidParams()) {
    message << "camera: model " << camera.ModelName() << " expects "
            << CameraModelNumParams(camera.model_id) << " parameters, got " << camera.params.size();
    return message.str();
  }
  if (camera.width == 0 || camera.height == 0) {
    message << "camera: image size " << camera.width << "x" << camera.height << " must be positive";
    return message.str();
  }
  for (size_t i = 0; i < camera.params.size(); ++i) {
    if (!std::isfinite(camera.params[i])) {
      message << "camera: parameter " << i << " is not finite";
      return message.str();
    }
  }
  for (const int index : FocalLengthIndices(camera)) {
    if (!(camera.params[index] > 0.0)) {
      message << "camera: focal length (parameter " << index << ") " << camera.params[index]
              << " must be > 0";
      return message.str();
    }
  }
  return "";
}

}  // namespace

std::string SensorRig::Validate() const {
  if (std::string error = ValidateCamera(camera); !error.empty()) return error;
  std::ostringstream message;
  const double norm = body_from_cam.rotation.norm();
  if (!(std::abs(norm - 1.0) <= kQuaternionNormTolerance)) {
    message << "body_from_cam.rotation: quaternion norm " << norm << " is not 1 (tolerance "
            << kQuaternionNormTolerance << ")";
    return message.str();
  }
  if (!body_from_cam.translation.allFinite()) {
    return "body_from_cam.translation: not finite";
  }
  if (std::string error = imu_noise.Validate(); !error.empty()) return "imu_noise: " + error;
  if (!(camera_rate_hz > 0.0) || !std::isfinite(camera_rate_hz)) {
    message << "camera_rate_hz: " << camera_rate_hz << " must be > 0";
    return message.str();
  }
  return "";
}

}  // namespace viosfm

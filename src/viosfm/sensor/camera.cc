#include "viosfm/sensor/camera.h"

#include <array>
#include <utility>

namespace viosfm {
namespace {

struct ModelInfo {
  CameraModelId id;
  const char* name;
  int num_params;
};

constexpr std::array<ModelInfo, 11> kModels = {{
    {CameraModelId::kSimplePinhole, "SIMPLE_PINHOLE", 3},
    {CameraModelId::kPinhole, "PINHOLE", 4},
    {CameraModelId::kSimpleRadial, "SIMPLE_RADIAL", 4},
    {CameraModelId::kRadial, "RADIAL", 5},
    {CameraModelId::kOpenCV, "OPENCV", 8},
    {CameraModelId::kOpenCVFisheye, "OPENCV_FISHEYE", 8},
    {CameraModelId::kFullOpenCV, "FULL_OPENCV", 12},
    {CameraModelId::kFOV, "FOV", 5},
    {CameraModelId::kSimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 4},
    {CameraModelId::kRadialFisheye, "RADIAL_FISHEYE", 5},
    {CameraModelId::kThinPrismFisheye, "THIN_PRISM_FISHEYE", 12},
}};

const ModelInfo* FindModel(CameraModelId id) {
  for (const auto& model : kModels) {
    if (model.id == id) return &model;
  }
  return nullptr;
}

}  // namespace

std::string CameraModelName(CameraModelId model_id) {
  const ModelInfo* model = FindModel(model_id);
  return model ? model->name : "";
}

CameraModelId CameraModelIdFromName(const std::string& name) {
  for (const auto& model : kModels) {
    if (name == model.name) return model.id;
  }
  return CameraModelId::kInvalid;
}

int CameraModelNumParams(CameraModelId model_id) {
  const ModelInfo* model = FindModel(model_id);
  return model ? model->num_params : -1;
}

bool IsKnownCameraModelId(int value) {
  return FindModel(static_cast<CameraModelId>(value)) != nullptr;
}

bool Camera::HasValidParams() const {
  const int expected = CameraModelNumParams(model_id);
  return expected >= 0 && params.size() == static_cast<size_t>(expected);
}

}  // namespace viosfm

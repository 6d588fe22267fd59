#include "viosfm/io/colmap_convention.h"

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

Camera ShiftPrincipalPoint(Camera camera, double offset) {
  VIOSFM_CHECK(camera.HasValidParams()) << "camera " << camera.camera_id;
  const int cx = PrincipalPointIndex(camera.model_id);
  camera.params[cx] += offset;
  camera.params[cx + 1] += offset;
  return camera;
}

}  // namespace

int PrincipalPointIndex(CameraModelId model_id) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole:
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kRadial:
    case CameraModelId::kSimpleRadialFisheye:
    case CameraModelId::kRadialFisheye: return 1;
    default: return 2;
  }
}

Camera CameraToColmapConvention(Camera camera) {
  return ShiftPrincipalPoint(std::move(camera), kColmapPixelOffset);
}

Camera CameraFromColmapConvention(Camera camera) {
  return ShiftPrincipalPoint(std::move(camera), -kColmapPixelOffset);
}

}  // namespace viosfm

// Camera intrinsics: a model id (COLMAP's ids, names and parameter order, so
// models round-trip through COLMAP files) and its parameters.
// Projection, unprojection, distortion and their Jacobians are in
// camera_models.h.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viosfm/util/types.h"

namespace viosfm {

// COLMAP 3.8 model ids. Those viosfm can project with are marked (*).
enum class CameraModelId : int {
  kInvalid = -1,
  kSimplePinhole = 0,        // (*) f, cx, cy
  kPinhole = 1,              // (*) fx, fy, cx, cy
  kSimpleRadial = 2,         // (*) f, cx, cy, k
  kRadial = 3,               // (*) f, cx, cy, k1, k2
  kOpenCV = 4,               // (*) fx, fy, cx, cy, k1, k2, p1, p2 (radial-tangential)
  kOpenCVFisheye = 5,        // (*) fx, fy, cx, cy, k1, k2, k3, k4 (equidistant)
  kFullOpenCV = 6,           //     fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
  kFOV = 7,                  //     fx, fy, cx, cy, omega
  kSimpleRadialFisheye = 8,  // f, cx, cy, k
  kRadialFisheye = 9,        //     f, cx, cy, k1, k2
  kThinPrismFisheye = 10,    //   fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1
};

// "PINHOLE", "OPENCV", ...; empty for an unknown id.
std::string CameraModelName(CameraModelId model_id);
// kInvalid for an unknown name.
CameraModelId CameraModelIdFromName(const std::string& name);
// Number of parameters of a model; -1 for an unknown id.
int CameraModelNumParams(CameraModelId model_id);
// Whether an integer read from a file is a known model id.
bool IsKnownCameraModelId(int value);

struct Camera {
  camera_t camera_id = kInvalidCameraId;
  CameraModelId model_id = CameraModelId::kInvalid;
  uint64_t width = 0;   // pixels
  uint64_t height = 0;  // pixels
  std::vector<double> params;
  bool has_prior_focal_length = false;

  std::string ModelName() const { return CameraModelName(model_id); }
  // True if the model id is known and params has its number of values.
  bool HasValidParams() const;
};

}  // namespace viosfm

// Pixel coordinates: viosfm, like OpenCV, Kalibr and EuRoC calibrations,
// puts the centre of the top-left pixel at (0, 0); COLMAP puts it at
// (0.5, 0.5). Everything inside viosfm (keypoints, camera principal points,
// projections, the renderer) uses the (0, 0) convention; COLMAP's files
// (models and databases) are converted here, when they are read and written.
// The shift by 0.5 is exact in double precision for any coordinate of
// magnitude above 1e-15, so COLMAP files still round-trip byte for byte.
#pragma once

#include "viosfm/sensor/camera.h"

namespace viosfm {

// COLMAP's coordinate of a point minus viosfm's.
inline constexpr double kColmapPixelOffset = 0.5;

// Index of the principal point's x in the parameters of any COLMAP model
// (1 for the single-focal-length models, else 2).
int PrincipalPointIndex(CameraModelId model_id);

// The camera with its principal point moved from viosfm's convention to
// COLMAP's (+0.5), and back (-0.5). The camera's params must be valid.
Camera CameraToColmapConvention(Camera camera);
Camera CameraFromColmapConvention(Camera camera);

}  // namespace viosfm

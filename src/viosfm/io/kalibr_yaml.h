// The keys that EuRoC's sensor.yaml and Kalibr's camchain.yaml share
// (internal to io/: it takes a YamlMap). Both describe a camera as
//   camera_model: pinhole                   (the only supported projection; optional)
//   intrinsics: [fu, fv, cu, cv]
//   distortion_model: radial-tangential (radtan) -> OPENCV        fx fy cx cy k1 k2 p1 p2
//                     equidistant (equi)         -> OPENCV_FISHEYE fx fy cx cy k1 k2 k3 k4
//                     none (or key absent)       -> PINHOLE        fx fy cx cy
//   <coefficients key>: [4 numbers]          ([] or absent for none; EuRoC names it
//                                             distortion_coefficients, Kalibr distortion_coeffs)
//   resolution: [width, height]
// and a rigid transform as a 4x4 matrix (YamlMap::GetMatrix4).
#pragma once

#include <string>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/io/yaml_util.h"
#include "viosfm/sensor/camera.h"

namespace viosfm {

// The camera of the keys above (camera_id left invalid). Throws InputError
// naming the file, the key's line and what was expected.
Camera ReadKalibrCameraIntrinsics(const YamlMap& yaml, const std::string& coefficients_key);

// b_from_a from a 4x4 homogeneous matrix: the bottom row must be (0 0 0 1)
// and the top-left block a rotation within kFileRotationTolerance
// (io/rotation_checks.h), which is then projected onto the nearest rotation.
Rigid3d ReadRigidTransform(const YamlMap& yaml, const std::string& key);

}  // namespace viosfm

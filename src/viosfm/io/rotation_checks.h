// The one tolerance every reader in io/ applies to rotations read from a
// file, so that a pose file cannot be accepted by one reader and rejected by
// another:
//  - a quaternion (TUM, EuRoC, COLMAP model and database, Kalibr, a pose on
//    the command line) must have | |q| - 1 | <= kFileRotationTolerance; it is
//    then normalised. A file printed with 4 decimals (TUM's ground truth) is
//    off by about 1e-4; a norm off by more is not a rounding of a rotation
//    but a different number (a scaled, truncated or garbled quaternion).
//  - a rotation matrix (KITTI, EuRoC/Kalibr T_BS and T_cam_imu) must be
//    orthonormal, max |R^T R - I| <= kFileRotationTolerance, with determinant
//    +1 (a determinant -1 is a reflection, a mirrored frame); it is then
//    projected onto the nearest rotation.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace viosfm {

inline constexpr double kFileRotationTolerance = 1e-3;

// Empty if `q` is a unit quaternion within kFileRotationTolerance (so also
// finite and non-zero); otherwise what is wrong ("its norm is 1.2").
std::string CheckFileQuaternion(const Eigen::Quaterniond& q);

// Empty if `rotation` is a proper rotation within kFileRotationTolerance;
// otherwise what is wrong ("its determinant is -1: a reflection").
std::string CheckFileRotationMatrix(const Eigen::Matrix3d& rotation);

}  // namespace viosfm

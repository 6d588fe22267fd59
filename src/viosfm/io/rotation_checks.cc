#include "viosfm/io/rotation_checks.h"

#include <cmath>
#include <sstream>

namespace viosfm {

std::string CheckFileQuaternion(const Eigen::Quaterniond& q) {
  const double norm = q.norm();
  if (std::abs(norm - 1.0) <= kFileRotationTolerance) return "";
  std::ostringstream message;
  message << "its norm is " << norm << " (a unit quaternion is expected, to "
          << kFileRotationTolerance << ")";
  return message.str();
}

std::string CheckFileRotationMatrix(const Eigen::Matrix3d& rotation) {
  std::ostringstream message;
  if (!rotation.allFinite()) return "it has non-finite entries";
  const double determinant = rotation.determinant();
  if (!(determinant > 0.0)) {
    message << "its determinant is " << determinant
            << (determinant < 0.0 ? " (a reflection, not a rotation)" : " (singular)");
    return message.str();
  }
  const double deviation =
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation <= kFileRotationTolerance) return "";
  message << "it is not orthonormal: R^T R differs from the identity by up to " << deviation
          << " (tolerance " << kFileRotationTolerance << ")";
  return message.str();
}

}  // namespace viosfm

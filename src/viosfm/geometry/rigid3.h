// Rigid transformation b_from_a: x_b = rotation * x_a + translation.
// Rotation is a unit Hamilton quaternion (Eigen's convention, w x y z).
// Name variables by the frames they map: cam_from_world, world_from_body.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ostream>

namespace viosfm {

using Matrix3x4d = Eigen::Matrix<double, 3, 4>;

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
      : rotation(rotation), translation(translation) {}
  Rigid3d(const Eigen::Matrix3d& rotation_matrix, const Eigen::Vector3d& translation)
      : rotation(rotation_matrix), translation(translation) {}

  // [R | t] as a 3x4 matrix.
  Matrix3x4d ToMatrix() const;
  // From the top 3x4 block of a homogeneous matrix; the rotation is
  // re-orthonormalised (nearest rotation) so slightly noisy files are accepted.
  static Rigid3d FromMatrix(const Matrix3x4d& matrix);

  Rigid3d Inverse() const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return rotation * point + translation;
  }
};

// (c_from_b * b_from_a) = c_from_a.
Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a);

// Position of the origin of frame a expressed in frame b, for cam_from_world:
// the camera centre in world coordinates is CenterOf(cam_from_world) = -R^T t.
inline Eigen::Vector3d ProjectionCenter(const Rigid3d& cam_from_world) {
  return cam_from_world.rotation.inverse() * -cam_from_world.translation;
}

std::ostream& operator<<(std::ostream& stream, const Rigid3d& transform);

}  // namespace viosfm

// Similarity transformation b_from_a: x_b = scale * (rotation * x_a) + translation.
#pragma once

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

struct Sim3d {
  double scale = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Sim3d() = default;
  Sim3d(double scale, const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
      : scale(scale), rotation(rotation), translation(translation) {}
  explicit Sim3d(const Rigid3d& rigid)
      : scale(1.0), rotation(rigid.rotation), translation(rigid.translation) {}

  Matrix3x4d ToMatrix() const;
  Sim3d Inverse() const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return scale * (rotation * point) + translation;
  }
  // b_from_a applied to a pose a_from_frame: returns b_from_frame, with the
  // translation scaled (the frame's own orientation is only rotated).
  Rigid3d TransformPose(const Rigid3d& a_from_frame) const;
};

Sim3d operator*(const Sim3d& c_from_b, const Sim3d& b_from_a);

std::ostream& operator<<(std::ostream& stream, const Sim3d& transform);

}  // namespace viosfm

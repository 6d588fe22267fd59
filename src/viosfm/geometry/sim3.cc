#include "viosfm/geometry/sim3.h"

namespace viosfm {

Matrix3x4d Sim3d::ToMatrix() const {
  Matrix3x4d matrix;
  matrix.leftCols<3>() = scale * rotation.toRotationMatrix();
  matrix.col(3) = translation;
  return matrix;
}

Sim3d Sim3d::Inverse() const {
  const Eigen::Quaterniond inverse_rotation = rotation.inverse();
  return Sim3d(1.0 / scale, inverse_rotation, inverse_rotation * -translation / scale);
}

Rigid3d Sim3d::TransformPose(const Rigid3d& a_from_frame) const {
  return Rigid3d((rotation * a_from_frame.rotation).normalized(), *this * a_from_frame.translation);
}

Sim3d operator*(const Sim3d& c_from_b, const Sim3d& b_from_a) {
  return Sim3d(c_from_b.scale * b_from_a.scale,
               (c_from_b.rotation * b_from_a.rotation).normalized(),
               c_from_b.scale * (c_from_b.rotation * b_from_a.translation) + c_from_b.translation);
}

std::ostream& operator<<(std::ostream& stream, const Sim3d& transform) {
  const auto& q = transform.rotation;
  const auto& t = transform.translation;
  return stream << "Sim3d(s=" << transform.scale << ", q_wxyz=[" << q.w() << ", " << q.x() << ", "
                << q.y() << ", " << q.z() << "], t=[" << t.x() << ", " << t.y() << ", " << t.z()
                << "])";
}

}  // namespace viosfm

#include "viosfm/geometry/rigid3.h"

#include <Eigen/SVD>

namespace viosfm {

Matrix3x4d Rigid3d::ToMatrix() const {
  Matrix3x4d matrix;
  matrix.leftCols<3>() = rotation.toRotationMatrix();
  matrix.col(3) = translation;
  return matrix;
}

Rigid3d Rigid3d::FromMatrix(const Matrix3x4d& matrix) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(matrix.leftCols<3>(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  if (rotation.determinant() < 0) {
    Eigen::Matrix3d u = svd.matrixU();
    u.col(2) *= -1;
    rotation = u * svd.matrixV().transpose();
  }
  return Rigid3d(Eigen::Quaterniond(rotation).normalized(), matrix.col(3));
}

Rigid3d Rigid3d::Inverse() const {
  const Eigen::Quaterniond inverse_rotation = rotation.inverse();
  return Rigid3d(inverse_rotation, inverse_rotation * -translation);
}

Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a) {
  return Rigid3d((c_from_b.rotation * b_from_a.rotation).normalized(),
                 c_from_b.rotation * b_from_a.translation + c_from_b.translation);
}

std::ostream& operator<<(std::ostream& stream, const Rigid3d& transform) {
  const auto& q = transform.rotation;
  const auto& t = transform.translation;
  return stream << "Rigid3d(q_wxyz=[" << q.w() << ", " << q.x() << ", " << q.y() << ", " << q.z()
                << "], t=[" << t.x() << ", " << t.y() << ", " << t.z() << "])";
}

}  // namespace viosfm

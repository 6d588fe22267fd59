#include "viosfm/geometry/lie.h"

namespace viosfm {
namespace {

// Below this angle the coefficients of the Jacobians are evaluated by their
// Taylor series (truncation error < 1e-15); above it the closed forms lose at
// most ~eps / kSmallAngle^2 ~ 1e-14 to cancellation.
constexpr double kSmallAngle = 0.1;

// (1 - cos(theta)) / theta^2
double CoefficientA(double theta) {
  if (theta < kSmallAngle) {
    const double t2 = theta * theta;
    return 0.5 - t2 / 24.0 + t2 * t2 / 720.0 - t2 * t2 * t2 / 40320.0;
  }
  const double half_sin = std::sin(0.5 * theta);
  return 2.0 * half_sin * half_sin / (theta * theta);
}

// (theta - sin(theta)) / theta^3
double CoefficientB(double theta) {
  if (theta < kSmallAngle) {
    const double t2 = theta * theta;
    return 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0 - t2 * t2 * t2 / 362880.0;
  }
  return (theta - std::sin(theta)) / (theta * theta * theta);
}

// 1 / theta^2 - (1 + cos(theta)) / (2 * theta * sin(theta))
double CoefficientInverse(double theta) {
  if (theta < kSmallAngle) {
    const double t2 = theta * theta;
    return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1209600.0;
  }
  // (1 + cos) / (2 sin) = cot(theta / 2) / 2.
  return 1.0 / (theta * theta) - 0.5 / (theta * std::tan(0.5 * theta));
}

}  // namespace

Eigen::Matrix3d Hat(const Eigen::Vector3d& vector) {
  Eigen::Matrix3d matrix;
  matrix << 0.0, -vector.z(), vector.y(),  //
      vector.z(), 0.0, -vector.x(),        //
      -vector.y(), vector.x(), 0.0;
  return matrix;
}

Eigen::Vector3d Vee(const Eigen::Matrix3d& matrix) {
  return 0.5 * Eigen::Vector3d(matrix(2, 1) - matrix(1, 2), matrix(0, 2) - matrix(2, 0),
                               matrix(1, 0) - matrix(0, 1));
}

Eigen::Quaterniond So3Exp(const Eigen::Vector3d& omega) {
  return QuaternionExp<double>(omega).normalized();
}

Eigen::Vector3d So3Log(const Eigen::Quaterniond& rotation) {
  return QuaternionLog<double>(rotation);
}

Eigen::Matrix3d So3RightJacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d hat = Hat(omega);
  return Eigen::Matrix3d::Identity() - CoefficientA(theta) * hat + CoefficientB(theta) * hat * hat;
}

Eigen::Matrix3d So3RightJacobianInverse(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d hat = Hat(omega);
  return Eigen::Matrix3d::Identity() + 0.5 * hat + CoefficientInverse(theta) * hat * hat;
}

Eigen::Matrix3d So3LeftJacobian(const Eigen::Vector3d& omega) {
  return So3RightJacobian(-omega);
}

Eigen::Matrix3d So3LeftJacobianInverse(const Eigen::Vector3d& omega) {
  return So3RightJacobianInverse(-omega);
}

Rigid3d Se3Exp(const Vector6d& xi) {
  const Eigen::Vector3d phi = xi.head<3>();
  const Eigen::Vector3d rho = xi.tail<3>();
  return Rigid3d(So3Exp(phi), So3LeftJacobian(phi) * rho);
}

Vector6d Se3Log(const Rigid3d& transform) {
  const Eigen::Vector3d phi = So3Log(transform.rotation);
  Vector6d xi;
  xi.head<3>() = phi;
  xi.tail<3>() = So3LeftJacobianInverse(phi) * transform.translation;
  return xi;
}

Matrix6d Se3Adjoint(const Rigid3d& transform) {
  const Eigen::Matrix3d rotation = transform.rotation.toRotationMatrix();
  Matrix6d adjoint = Matrix6d::Zero();
  adjoint.topLeftCorner<3, 3>() = rotation;
  adjoint.bottomLeftCorner<3, 3>() = Hat(transform.translation) * rotation;
  adjoint.bottomRightCorner<3, 3>() = rotation;
  return adjoint;
}

double RotationAngleDeg(const Eigen::Quaterniond& rotation) {
  return 2.0 * std::atan2(rotation.vec().norm(), std::abs(rotation.w())) * kDegreesPerRadian;
}

}  // namespace viosfm

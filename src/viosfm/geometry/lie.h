// SO(3) and SE(3) exponential and logarithm maps, their Jacobians and the
// SE(3) adjoint.
//
// Conventions:
//  - Rotations are unit Hamilton quaternions (Eigen), tangents are rotation
//    vectors omega = angle * axis with the angle in [0, pi].
//  - Jacobians follow Forster et al. (IMU preintegration, TRO 2017):
//      Exp(phi + dphi) ~= Exp(phi) * Exp(Jr(phi) * dphi)
//      Exp(phi + dphi) ~= Exp(Jl(phi) * dphi) * Exp(phi)
//      Log(Exp(phi) * Exp(dphi)) ~= phi + Jr^-1(phi) * dphi
//    with Jl(phi) = Jr(-phi) = R(phi) * Jr(phi).
//  - SE(3) tangents are ordered [rotation (3); translation (3)] and
//    Se3Exp(xi) = [Exp(phi), Jl(phi) * rho] (the true SE(3) exponential).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Skew-symmetric matrix with Hat(a) * b = a x b.
Eigen::Matrix3d Hat(const Eigen::Vector3d& vector);
// Inverse of Hat; uses the antisymmetric part of the matrix.
Eigen::Vector3d Vee(const Eigen::Matrix3d& matrix);

// Rotation by |omega| radians about omega / |omega|.
Eigen::Quaterniond So3Exp(const Eigen::Vector3d& omega);
// Rotation vector of a (not necessarily normalised) quaternion; the angle is
// in [0, pi]. Accurate near the identity and near a half turn.
Eigen::Vector3d So3Log(const Eigen::Quaterniond& rotation);
// The rotation's angle in degrees, in [0, 180] (any quaternion norm > 0).
double RotationAngleDeg(const Eigen::Quaterniond& rotation);
inline constexpr double kDegreesPerRadian = 180.0 / M_PI;

Eigen::Matrix3d So3RightJacobian(const Eigen::Vector3d& omega);
Eigen::Matrix3d So3RightJacobianInverse(const Eigen::Vector3d& omega);
Eigen::Matrix3d So3LeftJacobian(const Eigen::Vector3d& omega);
Eigen::Matrix3d So3LeftJacobianInverse(const Eigen::Vector3d& omega);

// xi = [phi; rho]: rotation Exp(phi), translation Jl(phi) * rho.
Rigid3d Se3Exp(const Vector6d& xi);
// Inverse of Se3Exp (rotation angle in [0, pi]).
Vector6d Se3Log(const Rigid3d& transform);
// Ad(T) with Exp(Ad(T) * xi) = T * Exp(xi) * T^-1, for xi = [phi; rho]:
//   Ad(T) = [R, 0; Hat(t) * R, R].
Matrix6d Se3Adjoint(const Rigid3d& transform);

// Templated versions, for use inside Ceres AutoDiff functors (T = double or
// ceres::Jet). Every branch is smooth, so derivatives are exact also at the
// identity (where the rotation vector is computed by a Taylor expansion).

// Rotation vector of the quaternion q (any norm > 0). Angle in [0, pi].
template <typename T>
Eigen::Matrix<T, 3, 1> QuaternionLog(const Eigen::Quaternion<T>& q) {
  using std::atan2;
  using std::sqrt;
  // q and -q are the same rotation: use the one with w >= 0 so that the
  // half angle atan2(|v|, w) lies in [0, pi/2].
  const T sign = q.w() < T(0) ? T(-1) : T(1);
  const T w = sign * q.w();
  const Eigen::Matrix<T, 3, 1> v = sign * q.vec();
  const T sin_sq = v.squaredNorm();
  T scale;
  // Below this |v|^2 the Taylor series of 2 * atan(s / w) / s is exact to
  // double precision (the next term is of order |v|^4).
  if (sin_sq < T(1e-16)) {
    scale = T(2) / w - T(2) * sin_sq / (T(3) * w * w * w);
  } else {
    const T sin_half = sqrt(sin_sq);
    scale = T(2) * atan2(sin_half, w) / sin_half;
  }
  return scale * v;
}

// Same, on a raw Eigen-ordered quaternion array [x, y, z, w] (the memory
// layout of Eigen::Quaternion and of ceres::EigenQuaternionManifold).
template <typename T>
void QuaternionLogXyzw(const T* q_xyzw, T* omega) {
  const Eigen::Quaternion<T> q(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]);
  const Eigen::Matrix<T, 3, 1> log = QuaternionLog(q);
  omega[0] = log[0];
  omega[1] = log[1];
  omega[2] = log[2];
}

// Unit quaternion Exp(omega), templated.
template <typename T>
Eigen::Quaternion<T> QuaternionExp(const Eigen::Matrix<T, 3, 1>& omega) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta_sq = omega.squaredNorm();
  T w;
  T scale;  // sin(theta / 2) / theta
  if (theta_sq < T(1e-16)) {
    w = T(1) - theta_sq / T(8);
    scale = T(0.5) - theta_sq / T(48);
  } else {
    const T theta = sqrt(theta_sq);
    w = cos(theta / T(2));
    scale = sin(theta / T(2)) / theta;
  }
  const Eigen::Matrix<T, 3, 1> v = scale * omega;
  return Eigen::Quaternion<T>(w, v.x(), v.y(), v.z());
}

}  // namespace viosfm

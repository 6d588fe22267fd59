// Ceres IMU factor between two states from a preintegrated IMU interval.
//
// Parameter blocks per state (ImuStateParameters):
//   pose[7]       = [qx, qy, qz, qw, px, py, pz]: world_from_body, Eigen
//                   quaternion memory order; manifold: CreatePoseManifold()
//                   (EigenQuaternionManifold x R^3).
//   speed_bias[9] = [v (m/s, world), bg (rad/s), ba (m/s^2)].
//
// Residual (15), with the deltas corrected to the biases of state i
// (ImuPreintegration::Corrected) and g = gravity in world:
//   r_R  = Log(dR^T * R_i^T * R_j)
//   r_v  = R_i^T (v_j - v_i - g dt) - dv
//   r_p  = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2) - dp
//   r_bg = bg_j - bg_i,   r_ba = ba_j - ba_i
// weighted by the square-root information of ImuPreintegration's full 15x15
// covariance. Derivatives by automatic differentiation.
#pragma once

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/pose_parameters.h"
#include "viosfm/vio/imu_preintegration.h"

namespace viosfm {

// The Ceres parameter blocks of one ImuState.
struct ImuStateParameters {
  std::array<double, 7> pose{0, 0, 0, 1, 0, 0, 0};
  std::array<double, 9> speed_bias{};

  static ImuStateParameters FromState(const ImuState& state);
  // The state (timestamp left to the caller) with a normalised quaternion.
  ImuState ToState(timestamp_ns_t timestamp_ns = 0) const;
};

class ImuFactor {
 public:
  static constexpr int kNumResiduals = 15;

  explicit ImuFactor(const ImuPreintegration& preintegration,
                     const Eigen::Vector3d& gravity_in_world = GravityInWorld());

  // AutoDiff cost function with blocks (pose_i, speed_bias_i, pose_j,
  // speed_bias_j); copies what it needs from `preintegration`.
  static ceres::CostFunction* Create(const ImuPreintegration& preintegration,
                                     const Eigen::Vector3d& gravity_in_world = GravityInWorld());

  template <typename T>
  bool operator()(const T* pose_i, const T* speed_bias_i, const T* pose_j, const T* speed_bias_j,
                  T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_i(pose_i);
    const Eigen::Map<const Vector3T> p_i(pose_i + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q_j(pose_j);
    const Eigen::Map<const Vector3T> p_j(pose_j + 4);
    const Eigen::Map<const Vector3T> v_i(speed_bias_i);
    const Eigen::Map<const Vector3T> bg_i(speed_bias_i + 3);
    const Eigen::Map<const Vector3T> ba_i(speed_bias_i + 6);
    const Eigen::Map<const Vector3T> v_j(speed_bias_j);
    const Eigen::Map<const Vector3T> bg_j(speed_bias_j + 3);
    const Eigen::Map<const Vector3T> ba_j(speed_bias_j + 6);

    // Bias-corrected deltas.
    const Vector3T dbg = bg_i - linearization_gyro_bias_.cast<T>();
    const Vector3T dba = ba_i - linearization_accel_bias_.cast<T>();
    const Vector3T correction = dR_dbg_.cast<T>() * dbg;
    const Eigen::Quaternion<T> delta_R = delta_R_.cast<T>() * QuaternionExp(correction);
    const Vector3T delta_v = delta_v_.cast<T>() + dv_dbg_.cast<T>() * dbg + dv_dba_.cast<T>() * dba;
    const Vector3T delta_p = delta_p_.cast<T>() + dp_dbg_.cast<T>() * dbg + dp_dba_.cast<T>() * dba;

    const T dt = T(delta_t_s_);
    const Vector3T g = gravity_in_world_.cast<T>();
    const Eigen::Quaternion<T> q_i_inverse = q_i.conjugate();

    Eigen::Matrix<T, 15, 1> r;
    r.template segment<3>(0) =
        QuaternionLog(Eigen::Quaternion<T>(delta_R.conjugate() * q_i_inverse * q_j));
    r.template segment<3>(3) = q_i_inverse * Vector3T(v_j - v_i - g * dt) - delta_v;
    r.template segment<3>(6) =
        q_i_inverse * Vector3T(p_j - p_i - v_i * dt - T(0.5) * g * dt * dt) - delta_p;
    r.template segment<3>(9) = bg_j - bg_i;
    r.template segment<3>(12) = ba_j - ba_i;

    Eigen::Map<Eigen::Matrix<T, 15, 1>> weighted(residuals);
    weighted = sqrt_information_.cast<T>() * r;
    return true;
  }

 private:
  Eigen::Quaterniond delta_R_;
  Eigen::Vector3d delta_v_;
  Eigen::Vector3d delta_p_;
  double delta_t_s_;
  Eigen::Vector3d linearization_gyro_bias_;
  Eigen::Vector3d linearization_accel_bias_;
  Eigen::Matrix3d dR_dbg_;
  Eigen::Matrix3d dv_dbg_;
  Eigen::Matrix3d dv_dba_;
  Eigen::Matrix3d dp_dbg_;
  Eigen::Matrix3d dp_dba_;
  Matrix15d sqrt_information_;
  Eigen::Vector3d gravity_in_world_;
};

// The unweighted 15-D residual of ImuFactor at two states (for diagnostics
// and tests).
Eigen::Matrix<double, 15, 1> ImuResidual(
    const ImuPreintegration& preintegration, const ImuState& state_i, const ImuState& state_j,
    const Eigen::Vector3d& gravity_in_world = GravityInWorld());

}  // namespace viosfm

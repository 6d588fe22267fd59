#include "viosfm/vio/imu_factor.h"

namespace viosfm {

ImuStateParameters ImuStateParameters::FromState(const ImuState& state) {
  ImuStateParameters parameters;
  const Eigen::Quaterniond q = state.world_from_body.rotation.normalized();
  parameters.pose = {q.x(),
                     q.y(),
                     q.z(),
                     q.w(),
                     state.world_from_body.translation.x(),
                     state.world_from_body.translation.y(),
                     state.world_from_body.translation.z()};
  for (int k = 0; k < 3; ++k) {
    parameters.speed_bias[k] = state.velocity_in_world[k];
    parameters.speed_bias[3 + k] = state.gyro_bias[k];
    parameters.speed_bias[6 + k] = state.accel_bias[k];
  }
  return parameters;
}

ImuState ImuStateParameters::ToState(timestamp_ns_t timestamp_ns) const {
  ImuState state;
  state.timestamp_ns = timestamp_ns;
  state.world_from_body.rotation =
      Eigen::Quaterniond(pose[3], pose[0], pose[1], pose[2]).normalized();
  state.world_from_body.translation = Eigen::Vector3d(pose[4], pose[5], pose[6]);
  state.velocity_in_world = Eigen::Vector3d(speed_bias[0], speed_bias[1], speed_bias[2]);
  state.gyro_bias = Eigen::Vector3d(speed_bias[3], speed_bias[4], speed_bias[5]);
  state.accel_bias = Eigen::Vector3d(speed_bias[6], speed_bias[7], speed_bias[8]);
  return state;
}

ImuFactor::ImuFactor(const ImuPreintegration& preintegration,
                     const Eigen::Vector3d& gravity_in_world)
    : delta_R_(preintegration.delta_R()),
      delta_v_(preintegration.delta_v()),
      delta_p_(preintegration.delta_p()),
      delta_t_s_(preintegration.delta_t_s()),
      linearization_gyro_bias_(preintegration.linearization_gyro_bias()),
      linearization_accel_bias_(preintegration.linearization_accel_bias()),
      dR_dbg_(preintegration.dR_dbg()),
      dv_dbg_(preintegration.dv_dbg()),
      dv_dba_(preintegration.dv_dba()),
      dp_dbg_(preintegration.dp_dbg()),
      dp_dba_(preintegration.dp_dba()),
      sqrt_information_(preintegration.SqrtInformation()),
      gravity_in_world_(gravity_in_world) {}

ceres::CostFunction* ImuFactor::Create(const ImuPreintegration& preintegration,
                                       const Eigen::Vector3d& gravity_in_world) {
  return new ceres::AutoDiffCostFunction<ImuFactor, kNumResiduals, 7, 9, 7, 9>(
      new ImuFactor(preintegration, gravity_in_world));
}

Eigen::Matrix<double, 15, 1> ImuResidual(const ImuPreintegration& preintegration,
                                         const ImuState& state_i, const ImuState& state_j,
                                         const Eigen::Vector3d& gravity_in_world) {
  const ImuFactor factor(preintegration, gravity_in_world);
  const ImuStateParameters i = ImuStateParameters::FromState(state_i);
  const ImuStateParameters j = ImuStateParameters::FromState(state_j);
  Eigen::Matrix<double, 15, 1> weighted;
  factor(i.pose.data(), i.speed_bias.data(), j.pose.data(), j.speed_bias.data(), weighted.data());
  // weighted = L^-1 r with L L^T the covariance, so r = L * weighted.
  const Eigen::LLT<Matrix15d> llt(preintegration.FullCovariance());
  return llt.matrixL() * weighted;
}

}  // namespace viosfm

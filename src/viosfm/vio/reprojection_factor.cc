#include "viosfm/vio/reprojection_factor.h"

#include <ceres/manifold.h>

#include "viosfm/geometry/lie.h"

namespace viosfm {

ceres::CostFunction* InverseDepthReprojectionFactor::Create(
    const Eigen::Vector2d& anchor_normalized, const Eigen::Vector2d& target_normalized,
    const Rigid3d& body_from_cam, double sqrt_information) {
  return new ceres::AutoDiffCostFunction<InverseDepthReprojectionFactor, kNumResiduals, 7, 7, 1>(
      new InverseDepthReprojectionFactor(anchor_normalized, target_normalized, body_from_cam,
                                         sqrt_information));
}

InverseDepthReprojectionCost::InverseDepthReprojectionCost(const Eigen::Vector2d& anchor_normalized,
                                                           const Eigen::Vector2d& target_normalized,
                                                           const Rigid3d& body_from_cam,
                                                           double sqrt_information)
    : anchor_(anchor_normalized.x(), anchor_normalized.y(), 1.0),
      target_(target_normalized),
      R_bc_(body_from_cam.rotation.normalized().toRotationMatrix()),
      t_bc_(body_from_cam.translation),
      sqrt_information_(sqrt_information) {}

bool InverseDepthReprojectionCost::Evaluate(double const* const* parameters, double* residuals,
                                            double** jacobians) const {
  using RowMajor23 = Eigen::Matrix<double, 2, 3, Eigen::RowMajor>;
  const Eigen::Map<const Eigen::Quaterniond> q_a(parameters[0]);
  const Eigen::Map<const Eigen::Vector3d> p_a(parameters[0] + 4);
  const Eigen::Map<const Eigen::Quaterniond> q_t(parameters[1]);
  const Eigen::Map<const Eigen::Vector3d> p_t(parameters[1] + 4);
  const double rho = parameters[2][0];
  const Eigen::Matrix3d R_a = q_a.toRotationMatrix();
  const Eigen::Matrix3d R_t = q_t.toRotationMatrix();

  // Homogeneous chain (every point scaled by rho), as the functor.
  const Eigen::Vector3d x_body_a = R_bc_ * anchor_ + t_bc_ * rho;
  const Eigen::Vector3d x_world = R_a * x_body_a + p_a * rho;
  const Eigen::Vector3d x_world_rel = x_world - p_t * rho;
  const Eigen::Vector3d x_body_t = R_t.transpose() * x_world_rel;
  const Eigen::Vector3d x_cam = R_bc_.transpose() * (x_body_t - t_bc_ * rho);
  const double z = x_cam.z();
  if (std::abs(z) < 1e-12) return false;
  residuals[0] = sqrt_information_ * (x_cam.x() / z - target_.x());
  residuals[1] = sqrt_information_ * (x_cam.y() / z - target_.y());
  if (jacobians == nullptr) return true;

  RowMajor23 d_projection;
  d_projection << 1.0 / z, 0.0, -x_cam.x() / (z * z), 0.0, 1.0 / z, -x_cam.y() / (z * z);
  d_projection *= sqrt_information_;
  const RowMajor23 d_world = d_projection * R_bc_.transpose() * R_t.transpose();

  // Ceres' quaternion tangent delta is half the world-frame rotation vector:
  // R(delta) = Exp(2 delta) R.
  static const ceres::EigenQuaternionManifold quaternion_manifold;
  auto write_pose = [&](double* jacobian, const RowMajor23& d_theta, const RowMajor23& d_p,
                        const double* q) {
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> minus_jacobian;
    quaternion_manifold.MinusJacobian(q, minus_jacobian.data());
    Eigen::Map<Eigen::Matrix<double, 2, 7, Eigen::RowMajor>> J(jacobian);
    J.leftCols<4>() = 2.0 * d_theta * minus_jacobian;
    J.rightCols<3>() = d_p;
  };
  if (jacobians[0] != nullptr) {
    // d x_world / d theta_a = -[R_a x_body_a]x, d x_world / d p_a = rho I.
    const RowMajor23 d_theta = -d_world * Hat(R_a * x_body_a);
    write_pose(jacobians[0], d_theta, d_world * rho, parameters[0]);
  }
  if (jacobians[1] != nullptr) {
    // d x_body_t / d theta_t = R_t^T [x_world_rel]x, d x_body_t / d p_t = -rho R_t^T.
    const RowMajor23 d_body = d_projection * R_bc_.transpose();
    const RowMajor23 d_theta = d_body * R_t.transpose() * Hat(x_world_rel);
    write_pose(jacobians[1], d_theta, -rho * d_world, parameters[1]);
  }
  if (jacobians[2] != nullptr) {
    const Eigen::Vector3d d_x_world = R_a * t_bc_ + p_a;
    const Eigen::Vector3d d_x_cam =
        R_bc_.transpose() * (R_t.transpose() * (d_x_world - p_t) - t_bc_);
    const Eigen::Vector2d d_rho = d_projection * d_x_cam;
    jacobians[2][0] = d_rho[0];
    jacobians[2][1] = d_rho[1];
  }
  return true;
}

Eigen::Vector3d InverseDepthPointInWorld(const Rigid3d& world_from_body_anchor,
                                         const Rigid3d& body_from_cam,
                                         const Eigen::Vector2d& anchor_normalized,
                                         double inverse_depth) {
  const Eigen::Vector3d point_in_cam = anchor_normalized.homogeneous() / inverse_depth;
  return world_from_body_anchor * (body_from_cam * point_in_cam);
}

double InverseDepthOfPoint(const Rigid3d& world_from_body, const Rigid3d& body_from_cam,
                           const Eigen::Vector3d& point_in_world) {
  const Eigen::Vector3d point_in_cam = (world_from_body * body_from_cam).Inverse() * point_in_world;
  if (point_in_cam.z() <= 0.0) return -1.0;
  return 1.0 / point_in_cam.z();
}

}  // namespace viosfm

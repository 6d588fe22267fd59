// Ceres cost functors of bundle adjustment: the reprojection error of a 3D
// point in a camera, and the paper's relative-pose constraint between two
// consecutive cameras (its E_r, weighted by w = alpha exp(-beta c)).
//
// Parameter blocks (shared by both functors, so they act on the same poses):
//   cam_from_world pose: 7 doubles, the rotation quaternion in Eigen's memory
//     order [x, y, z, w] followed by the translation (m) (PoseParameters),
//     manifold CreatePoseManifold(): one block per camera, so that Ceres'
//     Schur complement works on 6x6 camera blocks (with rotation and
//     translation as two blocks it spends a quarter of the time looking up
//     3x3 cells);
//   point in world: 3 doubles (m);
//   camera parameters: the model's parameters, in its order (camera_models.h).
// Every functor is weighted by a square-root information matrix. Derivatives
// by automatic differentiation.
#pragma once

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/pose_parameters.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {

// Pose blocks (ToPoseParameters, CreatePoseManifold): geometry/pose_parameters.h.

// residual = sqrt_information * (observed - Project(params, cam_from_world * X)),
// in pixels for the identity weight. Blocks: (pose[7] (PoseParameters),
// point[3], params[CameraModel::kNumParams()]). The pixel convention is the
// camera's (viosfm: the centre of the top-left pixel is (0, 0)). A robust
// loss, if any, is added by the problem builder.
template <typename CameraModel>
class ReprojectionError {
 public:
  static constexpr int kNumResiduals = 2;

  explicit ReprojectionError(const Eigen::Vector2d& observed,
                             const Eigen::Matrix2d& sqrt_information = Eigen::Matrix2d::Identity())
      : observed_(observed), sqrt_information_(sqrt_information) {}

  static ceres::CostFunction* Create(
      const Eigen::Vector2d& observed,
      const Eigen::Matrix2d& sqrt_information = Eigen::Matrix2d::Identity()) {
    return new ceres::AutoDiffCostFunction<ReprojectionError, kNumResiduals, 7, 3,
                                           CameraModel::kNumParams()>(
        new ReprojectionError(observed, sqrt_information));
  }

  template <typename T>
  bool operator()(const T* pose, const T* point, const T* params, T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> cam_from_world_rotation(pose);
    const Eigen::Map<const Vector3T> cam_from_world_translation(pose + 4);
    const Eigen::Map<const Vector3T> point_in_world(point);
    const Vector3T point_in_cam =
        cam_from_world_rotation * point_in_world + cam_from_world_translation;
    Eigen::Matrix<T, 2, 1> pixel;
    CameraModel::Project(params, point_in_cam.data(), pixel.data());
    const Eigen::Matrix<T, 2, 1> error = observed_.cast<T>() - pixel;
    Eigen::Map<Eigen::Matrix<T, 2, 1>> weighted(residuals);
    weighted = sqrt_information_.cast<T>() * error;
    return true;
  }

 private:
  Eigen::Vector2d observed_;
  Eigen::Matrix2d sqrt_information_;
};

// The same residual with the camera parameters held (not a parameter block):
// blocks (pose[7], point[3]), with analytic Jacobians (the model's
// DistortJacobian): what bundle adjustment without intrinsics refinement
// uses, about three times cheaper to evaluate than the automatic
// derivatives of all 10 + kNumParams() parameters. The pose Jacobian is
// with respect to the 7 ambient coordinates at a unit quaternion (Ceres
// applies the manifold).
template <typename CameraModel>
class ReprojectionErrorConstantCamera final : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  // `params` (the camera's) must outlive the cost function: it is read, not
  // copied (a bundle adjustment holds millions of these).
  ReprojectionErrorConstantCamera(const Eigen::Vector2d& observed, const double* params,
                                  const Eigen::Matrix2d& sqrt_information)
      : observed_(observed), sqrt_information_(sqrt_information), params_(params) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* pose = parameters[0];
    const Eigen::Map<const Eigen::Quaterniond> rotation(pose);
    const Eigen::Map<const Eigen::Vector3d> translation(pose + 4);
    const Eigen::Map<const Eigen::Vector3d> point_in_world(parameters[1]);
    const Eigen::Vector3d point_in_cam = rotation * point_in_world + translation;
    Eigen::Vector2d pixel;
    CameraModel::Project(params_, point_in_cam.data(), pixel.data());
    Eigen::Map<Eigen::Vector2d> residual(residuals);
    residual = sqrt_information_ * (observed_ - pixel);
    if (jacobians == nullptr || (jacobians[0] == nullptr && jacobians[1] == nullptr)) {
      return true;
    }
    // d residual / d point_in_cam = -S diag(fx, fy) D [1/z 0 -u/z; 0 1/z -v/z],
    // D the distortion's Jacobian at the normalised point (u, v).
    const double inverse_z = 1.0 / point_in_cam.z();
    const double u = point_in_cam.x() * inverse_z;
    const double v = point_in_cam.y() * inverse_z;
    Eigen::Matrix2d d_distorted;
    CameraModel::DistortJacobian(params_ + CameraModel::kExtraIdx(), u, v, &d_distorted, nullptr);
    d_distorted.row(0) *= CameraModel::FocalX(params_);
    d_distorted.row(1) *= CameraModel::FocalY(params_);
    Eigen::Matrix<double, 2, 3> d_normalised;
    d_normalised << inverse_z, 0.0, -u * inverse_z, 0.0, inverse_z, -v * inverse_z;
    const Eigen::Matrix<double, 2, 3> d_point_in_cam =
        -sqrt_information_ * d_distorted * d_normalised;
    if (jacobians[0] != nullptr) {
      // R(q) X = X + 2 w (v x X) + 2 v x (v x X), q = (w, v):
      //   d/dv = -2 w [X]x + 2 (v X^T + (v . X) I - 2 X v^T),  d/dw = 2 v x X.
      const Eigen::Vector3d& x = point_in_world;
      const Eigen::Vector3d q_vec = rotation.vec();
      const double w = rotation.w();
      Eigen::Matrix3d skew_x;
      skew_x << 0.0, -x.z(), x.y(), x.z(), 0.0, -x.x(), -x.y(), x.x(), 0.0;
      Eigen::Matrix<double, 3, 4> d_rotated;
      d_rotated.leftCols<3>() =
          -2.0 * w * skew_x +
          2.0 * (q_vec * x.transpose() + q_vec.dot(x) * Eigen::Matrix3d::Identity() -
                 2.0 * x * q_vec.transpose());
      d_rotated.col(3) = 2.0 * q_vec.cross(x);
      Eigen::Map<Eigen::Matrix<double, 2, 7, Eigen::RowMajor>> d_pose(jacobians[0]);
      d_pose.leftCols<4>() = d_point_in_cam * d_rotated;
      d_pose.rightCols<3>() = d_point_in_cam;
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> d_point(jacobians[1]);
      d_point = d_point_in_cam * rotation.toRotationMatrix();
    }
    return true;
  }

 private:
  Eigen::Vector2d observed_;
  Eigen::Matrix2d sqrt_information_;
  const double* params_;
};

// ReprojectionError<Model>::Create for the model of `model_id`; throws
// InputError for a model that cannot project.
ceres::CostFunction* CreateReprojectionCost(
    CameraModelId model_id, const Eigen::Vector2d& observed,
    const Eigen::Matrix2d& sqrt_information = Eigen::Matrix2d::Identity());

// ReprojectionErrorConstantCamera<Model>::Create for `camera` (its model and
// parameters, which must outlive the cost function); throws InputError for
// a model that cannot project.
ceres::CostFunction* CreateConstantCameraReprojectionCost(
    const Camera& camera, const Eigen::Vector2d& observed,
    const Eigen::Matrix2d& sqrt_information = Eigen::Matrix2d::Identity());

// The paper's balancing factor w = alpha * exp(-beta * c), c = number of
// verified matches between the two frames (alpha = 1e3, beta = 0.003 in the
// paper): the fewer the matches, the more the VIO prior counts.
double RelativePoseWeight(int num_verified_matches, double alpha, double beta);

// E_r = || Log(p_12 * p_hat_12^-1) ||^2 between two cameras with poses
// cam1_from_world and cam2_from_world, where p_12 = cam2_from_world *
// cam1_from_world^-1 is their relative pose (cam2_from_cam1) and p_hat_12
// the VIO's. With E = p_12 * p_hat_12^-1 = (R_E, t_E), the unweighted
// residual is
//   r = [ Log(R_E) (rad, 3) ; t_E (m, 3) ],   t_E = t_12 - R_E * t_hat_12,
// and the functor returns sqrt_information * r (see
// RelativePoseSqrtInformation). Blocks: (pose1[7], pose2[7]), the two
// cam_from_world poses as PoseParameters.
class RelativePoseError {
 public:
  static constexpr int kNumResiduals = 6;

  RelativePoseError(const Rigid3d& cam2_from_cam1,
                    const Eigen::Matrix<double, 6, 6>& sqrt_information);

  static ceres::CostFunction* Create(const Rigid3d& cam2_from_cam1,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_information);

  template <typename T>
  bool operator()(const T* pose1, const T* pose2, T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q1(pose1);
    const Eigen::Map<const Vector3T> t1(pose1 + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q2(pose2);
    const Eigen::Map<const Vector3T> t2(pose2 + 4);
    // cam2_from_cam1 = cam2_from_world * world_from_cam1.
    const Eigen::Quaternion<T> q12 = q2 * q1.conjugate();
    const Vector3T t12 = t2 - q12 * t1;
    // E = p_12 * p_hat_12^-1.
    const Eigen::Quaternion<T> q_error = q12 * prior_rotation_inverse_.cast<T>();
    const Vector3T t_error = t12 - q_error * prior_translation_.cast<T>();
    Eigen::Matrix<T, 6, 1> error;
    error.template head<3>() = QuaternionLog(q_error);
    error.template tail<3>() = t_error;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> weighted(residuals);
    weighted = sqrt_information_.cast<T>() * error;
    return true;
  }

 private:
  Eigen::Quaterniond prior_rotation_inverse_;
  Eigen::Vector3d prior_translation_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

// diag(sqrt(w) / rotation_sigma_rad (x3), sqrt(w) / translation_sigma_m (x3)),
// so that the cost is w * (|Log R_E|^2 / sigma_rot^2 + |t_E|^2 / sigma_trans^2):
// the sigmas set the relative scale of rotation and translation and the
// unit in which the paper's w applies (see BundleAdjustmentOptions).
Eigen::Matrix<double, 6, 6> RelativePoseSqrtInformation(double weight, double rotation_sigma_rad,
                                                        double translation_sigma_m);

// The unweighted 6-D residual r = [Log(R_E); t_E] of RelativePoseError (for
// diagnostics and tests).
Eigen::Matrix<double, 6, 1> RelativePoseResidual(const Rigid3d& cam1_from_world,
                                                 const Rigid3d& cam2_from_world,
                                                 const Rigid3d& prior_cam2_from_cam1);

}  // namespace viosfm

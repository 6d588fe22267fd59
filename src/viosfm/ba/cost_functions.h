// Ceres cost functors of bundle adjustment: the reprojection error of a 3D
// point in a camera, and the paper's relative-pose constraint between two
// consecutive cameras (its E_r, weighted by w = alpha exp(-beta c)).
//
// Parameter blocks (shared by both functors, so they act on the same poses):
//   cam_from_world rotation: 4 doubles, Eigen quaternion memory order
//     [x, y, z, w] (Rigid3d::rotation.coeffs()), manifold
//     ceres::EigenQuaternionManifold;
//   cam_from_world translation: 3 doubles (m);
//   point in world: 3 doubles (m);
//   camera parameters: the model's parameters, in its order (camera_models.h).
// Every functor is weighted by a square-root information matrix. Derivatives
// by automatic differentiation.
#pragma once

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "viosfm/geometry/lie.h"
#include "viosfm/geometry/rigid3.h"
#include "viosfm/sensor/camera_models.h"

namespace viosfm {

// residual = sqrt_information * (observed - Project(params, cam_from_world * X)),
// in pixels for the identity weight. Blocks: (rotation[4], translation[3],
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
    return new ceres::AutoDiffCostFunction<ReprojectionError, kNumResiduals, 4, 3, 3,
                                           CameraModel::kNumParams()>(
        new ReprojectionError(observed, sqrt_information));
  }

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* point, const T* params,
                  T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> cam_from_world_rotation(rotation);
    const Eigen::Map<const Vector3T> cam_from_world_translation(translation);
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

// ReprojectionError<Model>::Create for the model of `model_id`; throws
// InputError for a model that cannot project.
ceres::CostFunction* CreateReprojectionCost(
    CameraModelId model_id, const Eigen::Vector2d& observed,
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
// RelativePoseSqrtInformation). Blocks: (rotation1[4], translation1[3],
// rotation2[4], translation2[3]) of the two cam_from_world poses.
class RelativePoseError {
 public:
  static constexpr int kNumResiduals = 6;

  RelativePoseError(const Rigid3d& cam2_from_cam1,
                    const Eigen::Matrix<double, 6, 6>& sqrt_information);

  static ceres::CostFunction* Create(const Rigid3d& cam2_from_cam1,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_information);

  template <typename T>
  bool operator()(const T* rotation1, const T* translation1, const T* rotation2,
                  const T* translation2, T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q1(rotation1);
    const Eigen::Map<const Vector3T> t1(translation1);
    const Eigen::Map<const Eigen::Quaternion<T>> q2(rotation2);
    const Eigen::Map<const Vector3T> t2(translation2);
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

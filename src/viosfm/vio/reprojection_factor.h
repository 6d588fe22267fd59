// Ceres reprojection factor of a landmark parameterised by its inverse depth
// in the camera of its first (anchor) observation.
//
// Parameter blocks: pose_anchor[7], pose_target[7] (world_from_body, the
// layout of ImuStateParameters::pose, manifold CreatePoseManifold()) and
// inverse_depth[1] (1/m, the inverse of the z coordinate of the landmark in
// the anchor camera). The camera-IMU extrinsics body_from_cam are constant.
//
// With the anchor observation u_a (undistorted normalised coordinates, the
// bearing (u_a, 1)) and rho the inverse depth:
//   x_cam_a   = (u_a, 1) / rho
//   x_world   = world_from_body_a * body_from_cam * x_cam_a
//   x_cam_t   = (world_from_body_t * body_from_cam)^-1 * x_world
//   residual  = sqrt_information * (x_cam_t.xy / x_cam_t.z - u_t)
// where u_t is the observation in the target frame. The square-root
// information is isotropic: focal_px / sigma_px turns normalised
// coordinates into standard deviations of a pixel error. Derivatives by
// automatic differentiation.
#pragma once

#include <ceres/autodiff_cost_function.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "viosfm/geometry/rigid3.h"

namespace viosfm {

class InverseDepthReprojectionFactor {
 public:
  static constexpr int kNumResiduals = 2;

  InverseDepthReprojectionFactor(const Eigen::Vector2d& anchor_normalized,
                                 const Eigen::Vector2d& target_normalized,
                                 const Rigid3d& body_from_cam, double sqrt_information)
      : anchor_(anchor_normalized.x(), anchor_normalized.y(), 1.0),
        target_(target_normalized),
        body_from_cam_rotation_(body_from_cam.rotation.normalized()),
        body_from_cam_translation_(body_from_cam.translation),
        sqrt_information_(sqrt_information) {}

  // AutoDiff cost function with blocks (pose_anchor, pose_target, inverse_depth).
  // sqrt_information = focal length (px) / pixel standard deviation (px).
  static ceres::CostFunction* Create(const Eigen::Vector2d& anchor_normalized,
                                     const Eigen::Vector2d& target_normalized,
                                     const Rigid3d& body_from_cam, double sqrt_information);

  template <typename T>
  bool operator()(const T* pose_anchor, const T* pose_target, const T* inverse_depth,
                  T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(pose_anchor);
    const Eigen::Map<const Vector3T> p_a(pose_anchor + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q_t(pose_target);
    const Eigen::Map<const Vector3T> p_t(pose_target + 4);
    const Eigen::Quaternion<T> q_bc = body_from_cam_rotation_.cast<T>();
    const Vector3T t_bc = body_from_cam_translation_.cast<T>();

    // Homogeneous form: scaling every point by rho keeps the projection and
    // avoids dividing by rho (finite also for points at infinity).
    const T rho = inverse_depth[0];
    const Vector3T x_body_a = q_bc * anchor_.cast<T>() + t_bc * rho;
    const Vector3T x_world = q_a * x_body_a + p_a * rho;
    const Vector3T x_body_t = q_t.conjugate() * Vector3T(x_world - p_t * rho);
    const Vector3T x_cam_t = q_bc.conjugate() * Vector3T(x_body_t - t_bc * rho);

    const T sqrt_information = T(sqrt_information_);
    residuals[0] = sqrt_information * (x_cam_t.x() / x_cam_t.z() - T(target_.x()));
    residuals[1] = sqrt_information * (x_cam_t.y() / x_cam_t.z() - T(target_.y()));
    return true;
  }

 private:
  Eigen::Vector3d anchor_;
  Eigen::Vector2d target_;
  Eigen::Quaterniond body_from_cam_rotation_;
  Eigen::Vector3d body_from_cam_translation_;
  double sqrt_information_;
};

// The same residual with analytic Jacobians (several times faster than the
// automatic differentiation of InverseDepthReprojectionFactor, which the
// tests use as the reference). The ambient pose Jacobian is the tangent one
// times the quaternion manifold's MinusJacobian, so that Ceres' product with
// the PlusJacobian gives back the tangent Jacobian.
class InverseDepthReprojectionCost : public ceres::SizedCostFunction<2, 7, 7, 1> {
 public:
  InverseDepthReprojectionCost(const Eigen::Vector2d& anchor_normalized,
                               const Eigen::Vector2d& target_normalized,
                               const Rigid3d& body_from_cam, double sqrt_information);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d anchor_;
  Eigen::Vector2d target_;
  Eigen::Matrix3d R_bc_;
  Eigen::Vector3d t_bc_;
  double sqrt_information_;
};

// The reprojection error of a fixed world point (a landmark of the map the
// window kept before a reset) in a frame: the re-localisation of a
// restarted window against the previous segment. Block: pose[7]
// (world_from_body). residual = sqrt_information * (x_cam.xy / x_cam.z - u).
class MapPointReprojectionFactor {
 public:
  MapPointReprojectionFactor(const Eigen::Vector3d& point_in_world,
                             const Eigen::Vector2d& observed_normalized,
                             const Rigid3d& body_from_cam, double sqrt_information)
      : point_(point_in_world),
        observed_(observed_normalized),
        body_from_cam_rotation_(body_from_cam.rotation.normalized()),
        body_from_cam_translation_(body_from_cam.translation),
        sqrt_information_(sqrt_information) {}

  static ceres::CostFunction* Create(const Eigen::Vector3d& point_in_world,
                                     const Eigen::Vector2d& observed_normalized,
                                     const Rigid3d& body_from_cam, double sqrt_information) {
    return new ceres::AutoDiffCostFunction<MapPointReprojectionFactor, 2, 7>(
        new MapPointReprojectionFactor(point_in_world, observed_normalized, body_from_cam,
                                       sqrt_information));
  }

  template <typename T>
  bool operator()(const T* pose, T* residuals) const {
    using Vector3T = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q(pose);
    const Eigen::Map<const Vector3T> p(pose + 4);
    const Vector3T x_body = q.conjugate() * Vector3T(point_.cast<T>() - p);
    const Vector3T x_cam = body_from_cam_rotation_.cast<T>().conjugate() *
                           Vector3T(x_body - body_from_cam_translation_.cast<T>());
    const T sqrt_information = T(sqrt_information_);
    residuals[0] = sqrt_information * (x_cam.x() / x_cam.z() - T(observed_.x()));
    residuals[1] = sqrt_information * (x_cam.y() / x_cam.z() - T(observed_.y()));
    return true;
  }

 private:
  Eigen::Vector3d point_;
  Eigen::Vector2d observed_;
  Eigen::Quaterniond body_from_cam_rotation_;
  Eigen::Vector3d body_from_cam_translation_;
  double sqrt_information_;
};

// The landmark in the world frame from its anchor pose, anchor observation
// and inverse depth (rho > 0).
Eigen::Vector3d InverseDepthPointInWorld(const Rigid3d& world_from_body_anchor,
                                         const Rigid3d& body_from_cam,
                                         const Eigen::Vector2d& anchor_normalized,
                                         double inverse_depth);

// The inverse depth (1/z in the camera of world_from_body) of a world point;
// <= 0 when the point is not in front of the camera.
double InverseDepthOfPoint(const Rigid3d& world_from_body, const Rigid3d& body_from_cam,
                           const Eigen::Vector3d& point_in_world);

}  // namespace viosfm

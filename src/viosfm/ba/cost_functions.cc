#include "viosfm/ba/cost_functions.h"

#include <cmath>

#include "viosfm/util/errors.h"

namespace viosfm {

ceres::CostFunction* CreateReprojectionCost(CameraModelId model_id, const Eigen::Vector2d& observed,
                                            const Eigen::Matrix2d& sqrt_information) {
  return VisitCameraModel(model_id, [&](auto model) -> ceres::CostFunction* {
    using Model = decltype(model);
    return ReprojectionError<Model>::Create(observed, sqrt_information);
  });
}

ceres::CostFunction* CreateConstantCameraReprojectionCost(const Camera& camera,
                                                          const Eigen::Vector2d& observed,
                                                          const Eigen::Matrix2d& sqrt_information) {
  return VisitCameraModel(camera.model_id, [&](auto model) -> ceres::CostFunction* {
    using Model = decltype(model);
    VIOSFM_CHECK(static_cast<int>(camera.params.size()) == Model::kNumParams())
        << camera.params.size() << " parameters for " << camera.ModelName();
    return new ReprojectionErrorConstantCamera<Model>(observed, camera.params.data(),
                                                      sqrt_information);
  });
}

double RelativePoseWeight(int num_verified_matches, double alpha, double beta) {
  VIOSFM_CHECK(num_verified_matches >= 0) << num_verified_matches;
  return alpha * std::exp(-beta * static_cast<double>(num_verified_matches));
}

RelativePoseError::RelativePoseError(const Rigid3d& cam2_from_cam1,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_information)
    : prior_rotation_inverse_(cam2_from_cam1.rotation.normalized().conjugate()),
      prior_translation_(cam2_from_cam1.translation),
      sqrt_information_(sqrt_information) {}

ceres::CostFunction* RelativePoseError::Create(
    const Rigid3d& cam2_from_cam1, const Eigen::Matrix<double, 6, 6>& sqrt_information) {
  return new ceres::AutoDiffCostFunction<RelativePoseError, kNumResiduals, 7, 7>(
      new RelativePoseError(cam2_from_cam1, sqrt_information));
}

Eigen::Matrix<double, 6, 6> RelativePoseSqrtInformation(double weight, double rotation_sigma_rad,
                                                        double translation_sigma_m) {
  VIOSFM_CHECK(weight >= 0.0) << weight;
  VIOSFM_CHECK(rotation_sigma_rad > 0.0 && translation_sigma_m > 0.0)
      << rotation_sigma_rad << " " << translation_sigma_m;
  const double sqrt_weight = std::sqrt(weight);
  Eigen::Matrix<double, 6, 1> diagonal;
  diagonal << Eigen::Vector3d::Constant(sqrt_weight / rotation_sigma_rad),
      Eigen::Vector3d::Constant(sqrt_weight / translation_sigma_m);
  return diagonal.asDiagonal();
}

Eigen::Matrix<double, 6, 1> RelativePoseResidual(const Rigid3d& cam1_from_world,
                                                 const Rigid3d& cam2_from_world,
                                                 const Rigid3d& prior_cam2_from_cam1) {
  const RelativePoseError functor(prior_cam2_from_cam1, Eigen::Matrix<double, 6, 6>::Identity());
  const PoseParameters pose1 = ToPoseParameters(cam1_from_world);
  const PoseParameters pose2 = ToPoseParameters(cam2_from_world);
  Eigen::Matrix<double, 6, 1> residual;
  functor(pose1.data(), pose2.data(), residual.data());
  return residual;
}

}  // namespace viosfm

#include "viosfm/ba/cost_functions.h"

#include <ceres/gradient_checker.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "viosfm/geometry/lie.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// Plausible parameters for each supported model (752 x 480 image).
std::vector<double> ParamsFor(CameraModelId model_id) {
  switch (model_id) {
    case CameraModelId::kSimplePinhole: return {455.0, 376.0, 240.0};
    case CameraModelId::kPinhole: return {458.6, 457.3, 367.2, 248.4};
    case CameraModelId::kSimpleRadial: return {455.0, 376.0, 240.0, -0.05};
    case CameraModelId::kRadial: return {455.0, 376.0, 240.0, -0.28, 0.07};
    case CameraModelId::kOpenCV: return {458.6, 457.3, 367.2, 248.4, -0.283, 0.074, 1.9e-4, 1.8e-5};
    case CameraModelId::kOpenCVFisheye:
      return {190.9, 190.4, 254.9, 256.9, 0.0034, 0.0341, -0.0477, 0.0181};
    default: break;
  }
  return {};
}

Rigid3d RandomPose(Random* random, double angle_rad, double translation_m) {
  const Eigen::Vector3d omega(random->Normal(0, angle_rad), random->Normal(0, angle_rad),
                              random->Normal(0, angle_rad));
  const Eigen::Vector3d translation(random->Normal(0, translation_m),
                                    random->Normal(0, translation_m),
                                    random->Normal(0, translation_m));
  return Rigid3d(So3Exp(omega), translation);
}

// Largest |analytic - numeric| over the entries of each local Jacobian
// block, relative to that block's largest numeric entry (at least 1). Ceres'
// own per-entry relative error is meaningless for entries that are zero up
// to rounding (e.g. 1e-16 against 1e-13).
double MaxScaledJacobianError(const ceres::GradientChecker::ProbeResults& results) {
  double worst = 0.0;
  for (size_t block = 0; block < results.local_jacobians.size(); ++block) {
    const auto& analytic = results.local_jacobians[block];
    const auto& numeric = results.local_numeric_jacobians[block];
    if (numeric.size() == 0) continue;
    const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
    worst = std::max(worst, (analytic - numeric).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

// Ridders' extrapolation from a small first step: its default first step
// (1 % of the parameter) overshoots on the distortion polynomials.
ceres::NumericDiffOptions CheckerOptions() {
  ceres::NumericDiffOptions options;
  options.ridders_relative_initial_step_size = 1e-4;
  return options;
}

// A random camera pose, a point 2-5 m in front of it and its observation in
// `camera`, off by N(0, noise_px) in each coordinate.
struct RandomObservation {
  Rigid3d cam_from_world;
  Eigen::Vector3d point_in_cam;
  Eigen::Vector3d point_in_world;
  Eigen::Vector2d observed;
};

RandomObservation MakeRandomObservation(const Camera& camera, double noise_px, Random* random) {
  RandomObservation o;
  o.cam_from_world = RandomPose(random, 0.3, 1.0);
  const double x = random->Uniform(-1, 1);
  const double y = random->Uniform(-1, 1);
  o.point_in_cam = Eigen::Vector3d(x, y, random->Uniform(2, 5));
  o.point_in_world = o.cam_from_world.Inverse() * o.point_in_cam;
  o.observed = *Project(camera, o.point_in_cam);
  if (noise_px > 0.0) {
    const double dx = random->Normal(0, noise_px);
    o.observed += Eigen::Vector2d(dx, random->Normal(0, noise_px));
  }
  return o;
}

const CameraModelId kSupportedModels[] = {
    CameraModelId::kSimplePinhole, CameraModelId::kPinhole, CameraModelId::kSimpleRadial,
    CameraModelId::kRadial,        CameraModelId::kOpenCV,  CameraModelId::kOpenCVFisheye};

TEST(ReprojectionError, ZeroAtTheTruthAndScaledBySqrtInformation) {
  Random random(1);
  for (const CameraModelId model_id : kSupportedModels) {
    const Camera camera = MakeCamera(model_id, 752, 480, ParamsFor(model_id));
    const auto [cam_from_world, point_in_cam, point_in_world, observed] =
        MakeRandomObservation(camera, 0.0, &random);

    std::unique_ptr<ceres::CostFunction> cost(CreateReprojectionCost(model_id, observed));
    ASSERT_EQ(cost->num_residuals(), 2);
    ASSERT_EQ(cost->parameter_block_sizes().front(), 7);
    ASSERT_EQ(cost->parameter_block_sizes().back(), static_cast<int>(camera.params.size()));
    const PoseParameters pose = ToPoseParameters(cam_from_world);
    const double* parameters[] = {pose.data(), point_in_world.data(), camera.params.data()};
    Eigen::Vector2d residual;
    ASSERT_TRUE(cost->Evaluate(parameters, residual.data(), nullptr));
    EXPECT_LT(residual.norm(), 1e-9) << camera.ModelName();

    // 3 px off in x with sqrt-information 2 I: residual (6, 0).
    const Eigen::Vector2d shifted = observed + Eigen::Vector2d(3.0, 0.0);
    std::unique_ptr<ceres::CostFunction> weighted(
        CreateReprojectionCost(model_id, shifted, 2.0 * Eigen::Matrix2d::Identity()));
    ASSERT_TRUE(weighted->Evaluate(parameters, residual.data(), nullptr));
    EXPECT_NEAR(residual.x(), 6.0, 1e-8) << camera.ModelName();
    EXPECT_NEAR(residual.y(), 0.0, 1e-8) << camera.ModelName();
  }
}

TEST(ReprojectionError, UnsupportedModelThrowsInputError) {
  EXPECT_THROW(CreateReprojectionCost(CameraModelId::kFullOpenCV, Eigen::Vector2d::Zero()),
               InputError);
}

TEST(ReprojectionError, JacobiansMatchNumericDifferentiationForEveryModel) {
  Random random(2);
  const std::unique_ptr<ceres::Manifold> pose_manifold(CreatePoseManifold());
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr, nullptr};
  for (const CameraModelId model_id : kSupportedModels) {
    const Camera camera = MakeCamera(model_id, 752, 480, ParamsFor(model_id));
    for (int trial = 0; trial < 3; ++trial) {
      const auto [cam_from_world, point_in_cam, point_in_world, observed] =
          MakeRandomObservation(camera, 2.0, &random);
      std::unique_ptr<ceres::CostFunction> cost(CreateReprojectionCost(model_id, observed));
      ceres::GradientChecker checker(cost.get(), &manifolds, CheckerOptions());
      const PoseParameters pose = ToPoseParameters(cam_from_world);
      const double* parameters[] = {pose.data(), point_in_world.data(), camera.params.data()};
      ceres::GradientChecker::ProbeResults results;
      checker.Probe(parameters, 1e-6, &results);
      ASSERT_EQ(results.return_value, true) << camera.ModelName();
      EXPECT_LT(MaxScaledJacobianError(results), 1e-8) << camera.ModelName() << "\n"
                                                       << results.error_log;
    }
  }
}

TEST(ReprojectionErrorConstantCamera, SameResidualAndJacobiansAsTheFullCost) {
  Random random(7);
  for (const CameraModelId model_id : kSupportedModels) {
    const Camera camera = MakeCamera(model_id, 752, 480, ParamsFor(model_id));
    const auto [cam_from_world, point_in_cam, point_in_world, observed] =
        MakeRandomObservation(camera, 2.0, &random);
    Eigen::Matrix2d sqrt_information;
    sqrt_information << 2.0, 0.5, 0.0, 1.5;
    for (const Eigen::Matrix2d& weight : {Eigen::Matrix2d::Identity().eval(), sqrt_information}) {
      std::unique_ptr<ceres::CostFunction> full(CreateReprojectionCost(model_id, observed, weight));
      std::unique_ptr<ceres::CostFunction> held(
          CreateConstantCameraReprojectionCost(camera, observed, weight));
      ASSERT_EQ(held->parameter_block_sizes(), (std::vector<int32_t>{7, 3}));
      const PoseParameters pose = ToPoseParameters(cam_from_world);
      const double* full_parameters[] = {pose.data(), point_in_world.data(), camera.params.data()};
      const double* held_parameters[] = {pose.data(), point_in_world.data()};
      Eigen::Vector2d full_residual;
      Eigen::Vector2d held_residual;
      Eigen::Matrix<double, 2, 7, Eigen::RowMajor> full_d_pose;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> full_d_point;
      Eigen::Matrix<double, 2, 7, Eigen::RowMajor> held_d_pose;
      Eigen::Matrix<double, 2, 3, Eigen::RowMajor> held_d_point;
      double* full_jacobians[] = {full_d_pose.data(), full_d_point.data(), nullptr};
      double* held_jacobians[] = {held_d_pose.data(), held_d_point.data()};
      ASSERT_TRUE(full->Evaluate(full_parameters, full_residual.data(), full_jacobians));
      ASSERT_TRUE(held->Evaluate(held_parameters, held_residual.data(), held_jacobians));
      EXPECT_GT(held_residual.norm(), 0.1) << camera.ModelName();
      EXPECT_LT((held_residual - full_residual).norm(), 1e-12) << camera.ModelName();
      EXPECT_LT((held_d_pose - full_d_pose).norm(), 1e-9 * full_d_pose.norm())
          << camera.ModelName();
      EXPECT_LT((held_d_point - full_d_point).norm(), 1e-9 * full_d_point.norm())
          << camera.ModelName();
    }
  }
}

TEST(PoseParameters, RoundTripAndLayout) {
  Random random(6);
  const Rigid3d cam_from_world = RandomPose(&random, 1.0, 3.0);
  const PoseParameters pose = ToPoseParameters(cam_from_world);
  // [x, y, z, w] of the unit quaternion, then the translation.
  const Eigen::Quaterniond q = cam_from_world.rotation.normalized();
  EXPECT_DOUBLE_EQ(pose[0], q.x());
  EXPECT_DOUBLE_EQ(pose[3], q.w());
  EXPECT_DOUBLE_EQ(pose[4], cam_from_world.translation.x());
  EXPECT_DOUBLE_EQ(pose[6], cam_from_world.translation.z());
  const Rigid3d back = FromPoseParameters(pose);
  EXPECT_LT(back.rotation.angularDistance(cam_from_world.rotation), 1e-12);
  EXPECT_LT((back.translation - cam_from_world.translation).norm(), 1e-15);

  // The manifold: 7 ambient, 6 tangent; a step moves the rotation by the
  // first three components (Ceres' quaternion convention: |delta| is half
  // the angle) and the translation by the last three.
  const std::unique_ptr<ceres::Manifold> manifold(CreatePoseManifold());
  EXPECT_EQ(manifold->AmbientSize(), 7);
  EXPECT_EQ(manifold->TangentSize(), 6);
  const double delta[6] = {0.0, 0.0, 0.1, 1.0, 2.0, 3.0};
  PoseParameters moved;
  ASSERT_TRUE(manifold->Plus(pose.data(), delta, moved.data()));
  const Rigid3d stepped = FromPoseParameters(moved);
  EXPECT_NEAR(stepped.rotation.angularDistance(cam_from_world.rotation), 0.2, 1e-12);
  EXPECT_LT((stepped.translation - cam_from_world.translation - Eigen::Vector3d(1, 2, 3)).norm(),
            1e-12);
}

TEST(RelativePoseWeight, PaperValues) {
  EXPECT_DOUBLE_EQ(RelativePoseWeight(0, 1e3, 0.003), 1000.0);
  EXPECT_NEAR(RelativePoseWeight(1000, 1e3, 0.003), 1000.0 * std::exp(-3.0), 1e-12);
  EXPECT_NEAR(RelativePoseWeight(1000, 1e3, 0.003), 49.787068367863943, 1e-12);
  EXPECT_NEAR(RelativePoseWeight(100, 1e3, 0.003), 740.81822068171788, 1e-10);
  // Decreasing in the number of matches.
  EXPECT_LT(RelativePoseWeight(201, 1e3, 0.003), RelativePoseWeight(200, 1e3, 0.003));
}

TEST(RelativePoseError, ZeroAtTheTruth) {
  Random random(3);
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3d cam1_from_world = RandomPose(&random, 1.0, 3.0);
    const Rigid3d cam2_from_world = RandomPose(&random, 1.0, 3.0);
    const Rigid3d cam2_from_cam1 = cam2_from_world * cam1_from_world.Inverse();
    EXPECT_LT(RelativePoseResidual(cam1_from_world, cam2_from_world, cam2_from_cam1).norm(), 1e-12);
    std::unique_ptr<ceres::CostFunction> cost(
        RelativePoseError::Create(cam2_from_cam1, RelativePoseSqrtInformation(1e3, 0.005, 0.01)));
    const PoseParameters pose1 = ToPoseParameters(cam1_from_world);
    const PoseParameters pose2 = ToPoseParameters(cam2_from_world);
    const double* parameters[] = {pose1.data(), pose2.data()};
    Eigen::Matrix<double, 6, 1> residual;
    ASSERT_TRUE(cost->Evaluate(parameters, residual.data(), nullptr));
    EXPECT_LT(residual.norm(), 1e-8);
  }
}

TEST(RelativePoseError, ResidualIsLogOfTheErrorTransformWeighted) {
  Random random(4);
  const Rigid3d cam1_from_world = RandomPose(&random, 1.0, 3.0);
  const Rigid3d cam2_from_world = RandomPose(&random, 1.0, 3.0);
  const Rigid3d truth = cam2_from_world * cam1_from_world.Inverse();
  // A prior off by a known error E^-1: p_12 * p_hat^-1 = E.
  const Eigen::Vector3d omega(0.01, -0.02, 0.005);
  const Eigen::Vector3d translation(0.03, 0.0, -0.01);
  const Rigid3d error(So3Exp(omega), translation);
  const Rigid3d prior = error.Inverse() * truth;
  const Eigen::Matrix<double, 6, 1> residual =
      RelativePoseResidual(cam1_from_world, cam2_from_world, prior);
  EXPECT_LT((residual.head<3>() - omega).norm(), 1e-12);
  EXPECT_LT((residual.tail<3>() - translation).norm(), 1e-12);

  // Weighted: sqrt(w) / sigma per component.
  const double weight = RelativePoseWeight(200, 1e3, 0.003);
  std::unique_ptr<ceres::CostFunction> cost(
      RelativePoseError::Create(prior, RelativePoseSqrtInformation(weight, 0.005, 0.01)));
  const PoseParameters pose1 = ToPoseParameters(cam1_from_world);
  const PoseParameters pose2 = ToPoseParameters(cam2_from_world);
  const double* parameters[] = {pose1.data(), pose2.data()};
  Eigen::Matrix<double, 6, 1> weighted;
  ASSERT_TRUE(cost->Evaluate(parameters, weighted.data(), nullptr));
  EXPECT_LT((weighted.head<3>() - std::sqrt(weight) / 0.005 * omega).norm(), 1e-9);
  EXPECT_LT((weighted.tail<3>() - std::sqrt(weight) / 0.01 * translation).norm(), 1e-9);
}

TEST(RelativePoseError, JacobiansMatchNumericDifferentiation) {
  Random random(5);
  const std::unique_ptr<ceres::Manifold> pose_manifold(CreatePoseManifold());
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), pose_manifold.get()};
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3d cam1_from_world = RandomPose(&random, 1.0, 3.0);
    const Rigid3d cam2_from_world = RandomPose(&random, 1.0, 3.0);
    // Near the truth (as in a converged adjustment) and far from it.
    const double error_scale = trial < 2 ? 1e-3 : 0.2;
    const Rigid3d prior =
        RandomPose(&random, error_scale, error_scale) * cam2_from_world * cam1_from_world.Inverse();
    std::unique_ptr<ceres::CostFunction> cost(
        RelativePoseError::Create(prior, RelativePoseSqrtInformation(1.0, 1.0, 1.0)));
    ceres::GradientChecker checker(cost.get(), &manifolds, CheckerOptions());
    const PoseParameters pose1 = ToPoseParameters(cam1_from_world);
    const PoseParameters pose2 = ToPoseParameters(cam2_from_world);
    const double* parameters[] = {pose1.data(), pose2.data()};
    ceres::GradientChecker::ProbeResults results;
    checker.Probe(parameters, 1e-6, &results);
    ASSERT_EQ(results.return_value, true);
    EXPECT_LT(MaxScaledJacobianError(results), 1e-8) << results.error_log;
  }
}

}  // namespace
}  // namespace viosfm

#include "viosfm/vio/reprojection_factor.h"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>

#include "viosfm/geometry/lie.h"
#include "viosfm/util/random.h"
#include "viosfm/vio/imu_factor.h"

namespace viosfm {
namespace {

Rigid3d RandomPose(Random& random, double translation_scale) {
  const Eigen::Vector3d omega(random.Normal(0, 0.3), random.Normal(0, 0.3), random.Normal(0, 0.3));
  const Eigen::Vector3d t(random.Normal(0, translation_scale), random.Normal(0, translation_scale),
                          random.Normal(0, translation_scale));
  return Rigid3d(So3Exp(omega), t);
}

std::array<double, 7> PoseBlock(const Rigid3d& pose) {
  ImuState state;
  state.world_from_body = pose;
  return ImuStateParameters::FromState(state).pose;
}

struct Scene {
  Rigid3d body_from_cam;
  Rigid3d world_from_anchor;
  Rigid3d world_from_target;
  Eigen::Vector3d point_in_world;
  Eigen::Vector2d anchor_normalized;
  Eigen::Vector2d target_normalized;
  double inverse_depth = 0.0;
};

Scene MakeScene(Random& random) {
  Scene scene;
  scene.body_from_cam =
      Rigid3d(So3Exp(Eigen::Vector3d(-1.2, 0.1, -1.5)), Eigen::Vector3d(0.05, 0.01, -0.02));
  scene.world_from_anchor = RandomPose(random, 0.2);
  scene.world_from_target = scene.world_from_anchor * RandomPose(random, 0.3);
  // A point 2 to 6 m in front of the anchor camera.
  const Eigen::Vector3d point_in_cam(random.Uniform(-1, 1), random.Uniform(-1, 1),
                                     random.Uniform(2, 6));
  scene.point_in_world = scene.world_from_anchor * (scene.body_from_cam * point_in_cam);
  scene.anchor_normalized = point_in_cam.hnormalized();
  scene.inverse_depth = 1.0 / point_in_cam.z();
  const Eigen::Vector3d in_target =
      (scene.world_from_target * scene.body_from_cam).Inverse() * scene.point_in_world;
  scene.target_normalized = in_target.hnormalized();
  return scene;
}

TEST(InverseDepthReprojectionFactor, ZeroResidualAtTruth) {
  Random random(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Scene scene = MakeScene(random);
    std::unique_ptr<ceres::CostFunction> cost(InverseDepthReprojectionFactor::Create(
        scene.anchor_normalized, scene.target_normalized, scene.body_from_cam, 300.0));
    const auto anchor = PoseBlock(scene.world_from_anchor);
    const auto target = PoseBlock(scene.world_from_target);
    const double* parameters[] = {anchor.data(), target.data(), &scene.inverse_depth};
    double residuals[2];
    ASSERT_TRUE(cost->Evaluate(parameters, residuals, nullptr));
    EXPECT_NEAR(residuals[0], 0.0, 1e-9);
    EXPECT_NEAR(residuals[1], 0.0, 1e-9);
    // The helpers agree with the parameterisation.
    EXPECT_LT((InverseDepthPointInWorld(scene.world_from_anchor, scene.body_from_cam,
                                        scene.anchor_normalized, scene.inverse_depth) -
               scene.point_in_world)
                  .norm(),
              1e-9);
    EXPECT_NEAR(
        InverseDepthOfPoint(scene.world_from_anchor, scene.body_from_cam, scene.point_in_world),
        scene.inverse_depth, 1e-12);
  }
}

TEST(InverseDepthReprojectionFactor, ResidualIsWeightedNormalisedError) {
  Random random(4);
  const Scene scene = MakeScene(random);
  const Eigen::Vector2d offset(0.002, -0.001);
  std::unique_ptr<ceres::CostFunction> cost(InverseDepthReprojectionFactor::Create(
      scene.anchor_normalized, scene.target_normalized + offset, scene.body_from_cam, 450.0));
  const auto anchor = PoseBlock(scene.world_from_anchor);
  const auto target = PoseBlock(scene.world_from_target);
  const double* parameters[] = {anchor.data(), target.data(), &scene.inverse_depth};
  double residuals[2];
  ASSERT_TRUE(cost->Evaluate(parameters, residuals, nullptr));
  EXPECT_NEAR(residuals[0], -450.0 * offset.x(), 1e-8);
  EXPECT_NEAR(residuals[1], -450.0 * offset.y(), 1e-8);
}

TEST(InverseDepthReprojectionFactor, JacobiansMatchNumericDifferences) {
  Random random(5);
  std::unique_ptr<ceres::Manifold> pose_manifold(CreatePoseManifold());
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), pose_manifold.get(),
                                                         nullptr};
  for (int trial = 0; trial < 5; ++trial) {
    const Scene scene = MakeScene(random);
    // Away from the truth: a perturbed observation and inverse depth.
    std::unique_ptr<ceres::CostFunction> cost(InverseDepthReprojectionFactor::Create(
        scene.anchor_normalized, scene.target_normalized + Eigen::Vector2d(0.01, -0.02),
        scene.body_from_cam, 300.0));
    ceres::NumericDiffOptions numeric_options;
    ceres::GradientChecker checker(cost.get(), &manifolds, numeric_options);
    const auto anchor = PoseBlock(scene.world_from_anchor);
    const auto target = PoseBlock(scene.world_from_target);
    const double inverse_depth = scene.inverse_depth * 1.3;
    const double* parameters[] = {anchor.data(), target.data(), &inverse_depth};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(parameters, 1e-6, &results)) << results.error_log;
    EXPECT_LT(results.maximum_relative_error, 1e-6);
  }
}

// The analytic cost agrees with the automatic differentiation in value and
// in the tangent-space Jacobians Ceres uses.
TEST(InverseDepthReprojectionCost, MatchesAutoDiffFactor) {
  Random random(6);
  std::unique_ptr<ceres::Manifold> pose_manifold(CreatePoseManifold());
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), pose_manifold.get(),
                                                         nullptr};
  for (int trial = 0; trial < 10; ++trial) {
    const Scene scene = MakeScene(random);
    const Eigen::Vector2d target = scene.target_normalized + Eigen::Vector2d(0.01, -0.02);
    std::unique_ptr<ceres::CostFunction> autodiff(InverseDepthReprojectionFactor::Create(
        scene.anchor_normalized, target, scene.body_from_cam, 300.0));
    InverseDepthReprojectionCost analytic(scene.anchor_normalized, target, scene.body_from_cam,
                                          300.0);
    const auto anchor = PoseBlock(scene.world_from_anchor);
    const auto target_pose = PoseBlock(scene.world_from_target);
    const double inverse_depth = scene.inverse_depth * 0.8;
    const double* parameters[] = {anchor.data(), target_pose.data(), &inverse_depth};
    ceres::NumericDiffOptions numeric_options;
    ceres::GradientChecker::ProbeResults reference;
    ceres::GradientChecker::ProbeResults results;
    ceres::GradientChecker(autodiff.get(), &manifolds, numeric_options)
        .Probe(parameters, 1e-6, &reference);
    EXPECT_TRUE(ceres::GradientChecker(&analytic, &manifolds, numeric_options)
                    .Probe(parameters, 1e-6, &results))
        << results.error_log;
    EXPECT_LT((results.residuals - reference.residuals).norm(), 1e-10);
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_LT((results.local_jacobians[k] - reference.local_jacobians[k]).cwiseAbs().maxCoeff(),
                1e-8 * (1.0 + reference.local_jacobians[k].cwiseAbs().maxCoeff()))
          << "block " << k;
    }
  }
}

}  // namespace
}  // namespace viosfm

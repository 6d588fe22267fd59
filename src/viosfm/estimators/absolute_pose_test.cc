#include "viosfm/estimators/absolute_pose.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

constexpr double kFocalPx = 460.0;

Rigid3d RandomPose(Random* random) {
  const Eigen::Vector3d axis =
      Eigen::Vector3d(random->Normal(), random->Normal(), random->Normal()).normalized();
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(random->Uniform(0.0, M_PI), axis));
  return Rigid3d(rotation, Eigen::Vector3d(random->Uniform(-2, 2), random->Uniform(-2, 2),
                                           random->Uniform(-2, 2)));
}

// Points in front of the camera (depth 2-8 m, within +-40 degrees), in world
// coordinates, with their normalised image points (noise in pixels).
void MakeCorrespondences(const Rigid3d& cam_from_world, int count, double noise_px,
                         Random* random, std::vector<Eigen::Vector2d>* image,
                         std::vector<Eigen::Vector3d>* world) {
  const Rigid3d world_from_cam = cam_from_world.Inverse();
  for (int i = 0; i < count; ++i) {
    const double depth = random->Uniform(2.0, 8.0);
    const Eigen::Vector3d in_cam(random->Uniform(-0.8, 0.8) * depth,
                                 random->Uniform(-0.6, 0.6) * depth, depth);
    world->push_back(world_from_cam * in_cam);
    image->push_back(in_cam.hnormalized() + Eigen::Vector2d(random->Normal(0, noise_px),
                                                            random->Normal(0, noise_px)) /
                                                kFocalPx);
  }
}

double PositionError(const Rigid3d& a, const Rigid3d& b) {
  return (ProjectionCenter(a) - ProjectionCenter(b)).norm();
}

TEST(P3P, RecoversTheExactPoseAmongItsSolutions) {
  Random random(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Rigid3d truth = RandomPose(&random);
    std::vector<Eigen::Vector2d> image;
    std::vector<Eigen::Vector3d> world;
    MakeCorrespondences(truth, 3, 0.0, &random, &image, &world);
    const std::vector<Rigid3d> solutions = P3PEstimator::Estimate(image, world);
    ASSERT_FALSE(solutions.empty()) << "trial " << trial;
    ASSERT_LE(solutions.size(), 4u);
    double best = 1e9;
    for (const Rigid3d& pose : solutions) {
      best = std::min(best, PositionError(pose, truth) + pose.rotation.angularDistance(truth.rotation));
      // Every solution reprojects the three points.
      std::vector<double> residuals;
      P3PEstimator::Residuals(image, world, pose, &residuals);
      for (const double r2 : residuals) EXPECT_LT(std::sqrt(r2) * kFocalPx, 1e-5);
    }
    // (Nearly double roots of the quartic cost digits in a few draws.)
    EXPECT_LT(best, 1e-4) << "trial " << trial;
  }
}

TEST(AbsolutePoseDlt, RecoversThePoseFromSixOrMorePoints) {
  Random random(4);
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3d truth = RandomPose(&random);
    std::vector<Eigen::Vector2d> image;
    std::vector<Eigen::Vector3d> world;
    MakeCorrespondences(truth, 20, 0.0, &random, &image, &world);
    const std::vector<Rigid3d> solutions = AbsolutePoseDltEstimator::Estimate(image, world);
    ASSERT_EQ(solutions.size(), 1u);
    EXPECT_LT(PositionError(solutions[0], truth), 1e-8);
    EXPECT_LT(solutions[0].rotation.angularDistance(truth.rotation), 1e-9);
  }
}

TEST(AbsolutePose, RansacWithOutliersAndNoise) {
  Random random(5);
  for (int trial = 0; trial < 10; ++trial) {
    const Rigid3d truth = RandomPose(&random);
    std::vector<Eigen::Vector2d> image;
    std::vector<Eigen::Vector3d> world;
    MakeCorrespondences(truth, 120, 1.0, &random, &image, &world);
    // 40 % outliers: image points anywhere in the view.
    for (int i = 0; i < 80; ++i) {
      image.emplace_back(random.Uniform(-0.8, 0.8), random.Uniform(-0.6, 0.6));
      world.push_back(world[random.UniformInt(0, 119)] +
                      Eigen::Vector3d(random.Normal(0, 1), random.Normal(0, 1), random.Normal(0, 1)));
    }
    AbsolutePoseOptions options;
    options.seed = trial;
    const AbsolutePoseResult result = EstimateAbsolutePose(image, world, kFocalPx, options);
    ASSERT_TRUE(result.success);
    EXPECT_GE(result.num_inliers, 115u);
    EXPECT_LE(result.num_inliers, 125u);
    // 1 px noise on 120 points at 2-8 m: a few millimetres.
    EXPECT_LT(PositionError(result.cam_from_world, truth), 0.02);
    EXPECT_LT(result.cam_from_world.rotation.angularDistance(truth.rotation), 0.003);
  }
}

TEST(AbsolutePose, PredictionIsScoredAndAWrongOneIsReplaced) {
  Random random(6);
  const Rigid3d truth = RandomPose(&random);
  std::vector<Eigen::Vector2d> image;
  std::vector<Eigen::Vector3d> world;
  MakeCorrespondences(truth, 100, 0.5, &random, &image, &world);
  AbsolutePoseOptions options;
  // A good prediction (1 mm, 0.2 mrad off): all inliers, few trials.
  const Rigid3d good(truth.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(2e-4, Eigen::Vector3d::UnitY())),
                     truth.translation + Eigen::Vector3d(0.001, 0, 0));
  const AbsolutePoseResult with_good = EstimateAbsolutePose(image, world, kFocalPx, options, good);
  EXPECT_GE(with_good.num_predicted_inliers, 98u);
  EXPECT_TRUE(with_good.success);
  EXPECT_LE(with_good.num_trials, options.min_num_trials);
  // A prediction 0.5 m off: few of its inliers, the images' pose is found.
  const Rigid3d bad(truth.rotation, truth.translation + Eigen::Vector3d(0.5, 0, 0));
  const AbsolutePoseResult with_bad = EstimateAbsolutePose(image, world, kFocalPx, options, bad);
  EXPECT_LT(with_bad.num_predicted_inliers, 20u);
  ASSERT_TRUE(with_bad.success);
  EXPECT_LT(PositionError(with_bad.cam_from_world, truth), 0.01);
  EXPECT_EQ(CountAbsolutePoseInliers(image, world, truth, kFocalPx, 8.0), 100u);
}

TEST(AbsolutePose, TooFewCorrespondencesFail) {
  Random random(7);
  const Rigid3d truth = RandomPose(&random);
  std::vector<Eigen::Vector2d> image;
  std::vector<Eigen::Vector3d> world;
  MakeCorrespondences(truth, 10, 0.5, &random, &image, &world);
  EXPECT_FALSE(EstimateAbsolutePose(image, world, kFocalPx, AbsolutePoseOptions()).success);
  AbsolutePoseOptions bad;
  bad.min_num_inliers = 2;
  EXPECT_NE(bad.Validate().find("min_num_inliers"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

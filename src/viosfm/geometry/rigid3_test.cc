#include "viosfm/geometry/rigid3.h"

#include <gtest/gtest.h>

#include "viosfm/geometry/sim3.h"

namespace viosfm {
namespace {

Rigid3d ExampleTransform() {
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
                 Eigen::Vector3d(0.5, -1.0, 2.0));
}

TEST(Rigid3d, InverseAndComposition) {
  const Rigid3d b_from_a = ExampleTransform();
  const Eigen::Vector3d x_a(1.0, 2.0, 3.0);
  const Eigen::Vector3d x_b = b_from_a * x_a;
  EXPECT_LT((b_from_a.Inverse() * x_b - x_a).norm(), 1e-12);
  const Rigid3d identity = b_from_a * b_from_a.Inverse();
  EXPECT_LT(identity.translation.norm(), 1e-12);
  EXPECT_NEAR(std::abs(identity.rotation.w()), 1.0, 1e-12);
  EXPECT_LT((b_from_a.ToMatrix() * x_a.homogeneous() - x_b).norm(), 1e-12);
}

TEST(Rigid3d, FromMatrixRoundTripsAndProjectsCentre) {
  const Rigid3d cam_from_world = ExampleTransform();
  const Rigid3d back = Rigid3d::FromMatrix(cam_from_world.ToMatrix());
  EXPECT_LT(back.rotation.angularDistance(cam_from_world.rotation), 1e-12);
  EXPECT_LT((back.translation - cam_from_world.translation).norm(), 1e-12);
  const Eigen::Vector3d center = ProjectionCenter(cam_from_world);
  EXPECT_LT((cam_from_world * center).norm(), 1e-12);
}

TEST(Sim3d, InverseComposeAndPose) {
  const Sim3d b_from_a(2.5, ExampleTransform().rotation, Eigen::Vector3d(1, 0, -1));
  const Eigen::Vector3d x(0.3, -0.2, 4.0);
  EXPECT_LT((b_from_a.Inverse() * (b_from_a * x) - x).norm(), 1e-12);
  const Sim3d composed = b_from_a * b_from_a.Inverse();
  EXPECT_NEAR(composed.scale, 1.0, 1e-12);
  EXPECT_LT(composed.translation.norm(), 1e-12);
  const Rigid3d a_from_frame = ExampleTransform();
  const Rigid3d b_from_frame = b_from_a.TransformPose(a_from_frame);
  EXPECT_LT((b_from_frame.translation - b_from_a * a_from_frame.translation).norm(), 1e-12);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/scene/trajectory.h"

#include <gtest/gtest.h>

namespace viosfm {
namespace {

TEST(Trajectory, CameraAndBodyFramesConvertBothWays) {
  const Rigid3d body_from_cam(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(0.05, -0.02, 0.01));
  Trajectory world_from_body;
  world_from_body.poses.push_back(
      {7, Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())),
                  Eigen::Vector3d(1, 2, 3))});
  const Trajectory world_from_cam = BodyToCameraTrajectory(world_from_body, body_from_cam);
  // The camera centre is the body origin plus the rotated lever arm.
  const Rigid3d& body = world_from_body.poses[0].world_from_frame;
  EXPECT_LT((world_from_cam.poses[0].world_from_frame.translation -
             (body.translation + body.rotation * body_from_cam.translation))
                .norm(),
            1e-12);
  const Trajectory back = CameraToBodyTrajectory(world_from_cam, body_from_cam);
  EXPECT_EQ(back.poses[0].timestamp_ns, 7);
  EXPECT_LT((back.poses[0].world_from_frame.translation - body.translation).norm(), 1e-12);
  EXPECT_LT(back.poses[0].world_from_frame.rotation.angularDistance(body.rotation), 1e-12);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/scene/trajectory.h"

namespace viosfm {
namespace {

Trajectory ChangeFrame(Trajectory trajectory, const Rigid3d& old_from_new) {
  for (StampedPose& pose : trajectory.poses) {
    pose.world_from_frame = pose.world_from_frame * old_from_new;
  }
  return trajectory;
}

}  // namespace

Trajectory CameraToBodyTrajectory(const Trajectory& world_from_cam, const Rigid3d& body_from_cam) {
  return ChangeFrame(world_from_cam, body_from_cam.Inverse());
}

Trajectory BodyToCameraTrajectory(const Trajectory& world_from_body, const Rigid3d& body_from_cam) {
  return ChangeFrame(world_from_body, body_from_cam);
}

}  // namespace viosfm

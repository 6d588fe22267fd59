#include "viosfm/scene/trajectory.h"

#include <algorithm>
#include <iterator>

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

std::optional<size_t> NearestPoseIndex(const Trajectory& trajectory, timestamp_ns_t t,
                                       timestamp_ns_t max_dt) {
  return NearestStampIndex(trajectory.poses, t, max_dt,
                           [](const StampedPose& pose) { return pose.timestamp_ns; });
}

std::optional<Rigid3d> InterpolatePose(const Trajectory& trajectory, timestamp_ns_t t,
                                       timestamp_ns_t max_gap) {
  const auto& poses = trajectory.poses;
  const auto it = std::lower_bound(
      poses.begin(), poses.end(), t,
      [](const StampedPose& pose, timestamp_ns_t stamp) { return pose.timestamp_ns < stamp; });
  if (it != poses.end() && it->timestamp_ns == t) return it->world_from_frame;
  if (it == poses.begin() || it == poses.end()) return std::nullopt;
  const StampedPose& before = *std::prev(it);
  const StampedPose& after = *it;
  if (after.timestamp_ns - before.timestamp_ns > max_gap) return std::nullopt;
  const double s = static_cast<double>(t - before.timestamp_ns) /
                   static_cast<double>(after.timestamp_ns - before.timestamp_ns);
  Rigid3d pose;
  pose.rotation = before.world_from_frame.rotation.slerp(s, after.world_from_frame.rotation);
  pose.translation =
      (1.0 - s) * before.world_from_frame.translation + s * after.world_from_frame.translation;
  return pose;
}

}  // namespace viosfm

// A trajectory: poses of a moving frame (camera or body) in a fixed world
// frame, ordered by time.
#pragma once

#include <optional>
#include <vector>

#include "viosfm/geometry/rigid3.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {

struct StampedPose {
  // Nanoseconds. For formats without stamps (KITTI) the row index.
  timestamp_ns_t timestamp_ns = 0;
  Rigid3d world_from_frame;
};

struct Trajectory {
  std::vector<StampedPose> poses;
  // False when the source file had no timestamps (KITTI); the stamps are then
  // row indices and only association by index makes sense.
  bool has_timestamps = true;

  size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
};

// Changes the moving frame of a trajectory through the camera-body
// extrinsics: world_from_body = world_from_cam * cam_from_body, and back.
Trajectory CameraToBodyTrajectory(const Trajectory& world_from_cam, const Rigid3d& body_from_cam);
Trajectory BodyToCameraTrajectory(const Trajectory& world_from_body, const Rigid3d& body_from_cam);

// The index of the pose nearest in time to `t` if at most `max_dt` away
// (of two equally near, the later).
std::optional<size_t> NearestPoseIndex(const Trajectory& trajectory, timestamp_ns_t t,
                                       timestamp_ns_t max_dt);

// The pose at `t`: the pose stamped `t`, or interpolated (linear position,
// slerp rotation) between the two poses around `t` when they are at most
// `max_gap` apart; none before the first or after the last pose.
std::optional<Rigid3d> InterpolatePose(const Trajectory& trajectory, timestamp_ns_t t,
                                       timestamp_ns_t max_gap);

}  // namespace viosfm

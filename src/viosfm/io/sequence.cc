#include "viosfm/io/sequence.h"

namespace viosfm {

Trajectory GroundTruthBodyTrajectory(const Sequence& sequence) {
  Trajectory trajectory;
  trajectory.poses.reserve(sequence.ground_truth.size());
  for (const GroundTruthState& state : sequence.ground_truth) {
    trajectory.poses.push_back({state.timestamp_ns, state.world_from_body});
  }
  return trajectory;
}

Trajectory GroundTruthCameraTrajectory(const Sequence& sequence) {
  Trajectory trajectory;
  trajectory.poses.reserve(sequence.ground_truth.size());
  for (const GroundTruthState& state : sequence.ground_truth) {
    trajectory.poses.push_back(
        {state.timestamp_ns, state.world_from_body * sequence.body_from_cam});
  }
  return trajectory;
}

}  // namespace viosfm

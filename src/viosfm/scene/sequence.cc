#include "viosfm/scene/sequence.h"

#include <algorithm>
#include <cstdint>

namespace viosfm {

std::string DatabaseImageName(const SequenceImage& image) {
  return image.path.filename().string();
}

ImuCoverage CheckImuCoverage(const Sequence& sequence) {
  ImuCoverage coverage;
  if (sequence.images.empty() || sequence.imu.empty()) return coverage;
  const timestamp_ns_t first_image = sequence.images.front().timestamp_ns;
  const timestamp_ns_t last_image = sequence.images.back().timestamp_ns;
  const timestamp_ns_t first_imu = sequence.imu.front().timestamp_ns;
  const timestamp_ns_t last_imu = sequence.imu.back().timestamp_ns;
  coverage.spans = "images span [" + std::to_string(first_image) + ", " +
                   std::to_string(last_image) + "] ns, IMU samples span [" +
                   std::to_string(first_imu) + ", " + std::to_string(last_imu) + "] ns";
  coverage.overlaps = !(last_imu < first_image || first_imu > last_image);
  coverage.complete = first_imu <= first_image && last_imu >= last_image;
  return coverage;
}

double EstimateFrameRateHz(const std::vector<SequenceImage>& images) {
  if (images.size() < 2) return 0.0;
  std::vector<timestamp_ns_t> intervals;
  intervals.reserve(images.size() - 1);
  for (size_t i = 1; i < images.size(); ++i) {
    // In uint64, so that stamps of any range (however far apart) cannot
    // overflow; the readers keep stamps within +-2^62 ns anyway.
    const uint64_t interval = static_cast<uint64_t>(images[i].timestamp_ns) -
                              static_cast<uint64_t>(images[i - 1].timestamp_ns);
    intervals.push_back(static_cast<timestamp_ns_t>(
        std::min<uint64_t>(interval, static_cast<uint64_t>(INT64_MAX))));
  }
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const timestamp_ns_t median = intervals[intervals.size() / 2];
  return median > 0 ? 1e9 / static_cast<double>(median) : 0.0;
}

Trajectory GroundTruthBodyTrajectory(const Sequence& sequence) {
  Trajectory trajectory;
  trajectory.poses.reserve(sequence.ground_truth.size());
  for (const GroundTruthState& state : sequence.ground_truth) {
    trajectory.poses.push_back({state.timestamp_ns, state.world_from_body});
  }
  return trajectory;
}

Trajectory GroundTruthCameraTrajectory(const Sequence& sequence) {
  return BodyToCameraTrajectory(GroundTruthBodyTrajectory(sequence), sequence.rig.body_from_cam);
}

}  // namespace viosfm

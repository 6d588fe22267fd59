#include "viosfm/vio/rolling_shutter.h"

#include <Eigen/Geometry>
#include <unordered_map>

#include "viosfm/util/timestamp.h"

namespace viosfm {

void CorrectRollingShutter(const FrameFeatures* previous, double readout_s, int height,
                           const Eigen::Vector3d& cam_angular_rate, FrameFeatures* current) {
  if (readout_s == 0.0 || height <= 0) return;
  std::unordered_map<uint64_t, const FeatureObservation*> previous_by_track;
  if (previous != nullptr) {
    previous_by_track.reserve(previous->observations.size());
    for (const FeatureObservation& observation : previous->observations) {
      previous_by_track.emplace(observation.track_id, &observation);
    }
  }
  const double frame_gap_s =
      previous != nullptr ? NsToSeconds(current->timestamp_ns - previous->timestamp_ns) : 0.0;
  for (FeatureObservation& observation : current->observations) {
    const double offset_s = RowTimeOffset(observation.pixel.y(), height, readout_s);
    const auto found = previous_by_track.find(observation.track_id);
    if (found != previous_by_track.end()) {
      const FeatureObservation& before = *found->second;
      const double elapsed_s =
          frame_gap_s + offset_s - RowTimeOffset(before.pixel.y(), height, readout_s);
      if (elapsed_s > 0.0) {
        const Eigen::Vector2d velocity = (observation.normalized - before.normalized) / elapsed_s;
        observation.normalized -= velocity * offset_s;
        continue;
      }
    }
    // A new corner: the gyro's rotation over its row's time offset.
    observation.normalized =
        RotateBearingToStamp(observation.normalized, cam_angular_rate, offset_s);
  }
}

}  // namespace viosfm

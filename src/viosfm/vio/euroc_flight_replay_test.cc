// The VIO on 90 frames (4.45 s, 1.43 m of path) of EuRoC V1_01 in flight,
// ../shared/data/euroc_v101_flight_4s (see its README): a moving start, the
// rotations and accelerations of a flying MAV, propeller vibration in the
// accelerometer. Judged against the folder's ground truth (vicon2gt,
// independent of viosfm): tracking from its initialisation to the last
// frame, the ATE after SE(3) and Sim(3) alignment, and the camera-IMU time
// offset (EuRoC's is close to 0; the calibration states 0).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/euroc.h"
#include "viosfm/util/testing.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {
namespace {

// The ground truth's position at `timestamp_ns` (IMU clock), interpolated
// linearly between its rows (200 Hz); nullopt outside them.
std::optional<Eigen::Vector3d> TruePosition(const std::vector<GroundTruthState>& truth,
                                            timestamp_ns_t timestamp_ns) {
  const auto after = std::lower_bound(
      truth.begin(), truth.end(), timestamp_ns,
      [](const GroundTruthState& state, timestamp_ns_t t) { return state.timestamp_ns < t; });
  if (after == truth.end() || after == truth.begin()) {
    if (after != truth.end() && after->timestamp_ns == timestamp_ns) {
      return after->world_from_body.translation;
    }
    return std::nullopt;
  }
  const auto before = after - 1;
  const double w = static_cast<double>(timestamp_ns - before->timestamp_ns) /
                   static_cast<double>(after->timestamp_ns - before->timestamp_ns);
  return (1.0 - w) * before->world_from_body.translation + w * after->world_from_body.translation;
}

double AteRmse(const std::vector<Eigen::Vector3d>& estimate,
               const std::vector<Eigen::Vector3d>& truth, bool with_scale) {
  const std::optional<Sim3d> truth_from_estimate = AlignPointsUmeyama(estimate, truth, with_scale);
  if (!truth_from_estimate) return INFINITY;
  double sum = 0.0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    sum += (truth[i] - *truth_from_estimate * estimate[i]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(estimate.size()));
}

TEST(EurocFlightReplay, TracksTheFlightWithinCentimetres) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_flight_4s");
  const Sequence sequence = ReadEurocDataset(root, EurocReadOptions{});
  ASSERT_EQ(sequence.images.size(), 90u);
  ASSERT_FALSE(sequence.ground_truth.empty());

  VioOptions options;  // the defaults of `viosfm vio`
  options.show_progress = false;
  const VioResult result = RunVio(sequence, options);
  const VioSummary& summary = result.summary;
  const auto count = [&](VioStatus status) {
    return summary.status_counts[static_cast<int>(status)];
  };
  std::cout << "EuRoC V1_01 flight, 90 frames: " << summary.message << "\n  "
            << summary.time_offset.message << "\n  tracking " << count(VioStatus::kTracking)
            << ", initializing " << count(VioStatus::kInitializing) << ", imu_only "
            << count(VioStatus::kImuOnly) << ", lost " << count(VioStatus::kLost) << "\n";

  // Tracking from the moving start's initialisation to the last frame.
  ASSERT_EQ(result.frames.size(), 90u);
  EXPECT_EQ(summary.num_resets, 0);
  EXPECT_EQ(count(VioStatus::kImuOnly), 0u);
  EXPECT_EQ(count(VioStatus::kLost), 0u);
  const auto first_tracking = std::find_if(
      result.frames.begin(), result.frames.end(),
      [](const VioFrameResult& frame) { return frame.status == VioStatus::kTracking; });
  ASSERT_NE(first_tracking, result.frames.end());
  EXPECT_LE(NsToSeconds(first_tracking->timestamp_ns - sequence.images.front().timestamp_ns), 1.0);
  for (auto it = first_tracking; it != result.frames.end(); ++it) {
    EXPECT_EQ(it->status, VioStatus::kTracking)
        << "frame at " << NsToSeconds(it->timestamp_ns - sequence.images.front().timestamp_ns)
        << " s: " << VioStatusName(it->status);
  }

  // The camera-IMU time offset: within 5 ms of EuRoC's (about 0), whether
  // estimated or the calibration's kept.
  EXPECT_LE(std::abs(NsToSeconds(summary.time_offset.offset_ns)), 0.005)
      << summary.time_offset.message;
  if (!summary.time_offset.estimated) {
    EXPECT_EQ(summary.time_offset.offset_ns, sequence.rig.cam_time_offset_ns);
  }

  // ATE over every posed frame (1.43 m of path).
  std::vector<Eigen::Vector3d> estimate, truth;
  for (const VioFrameResult& frame : result.frames) {
    if (!frame.has_pose) continue;
    const std::optional<Eigen::Vector3d> true_position =
        TruePosition(sequence.ground_truth, frame.state.timestamp_ns);
    ASSERT_TRUE(true_position.has_value());
    estimate.push_back(frame.state.world_from_body.translation);
    truth.push_back(*true_position);
  }
  ASSERT_GE(estimate.size(), 80u);
  const double ate_se3_m = AteRmse(estimate, truth, false);
  const double ate_sim3_m = AteRmse(estimate, truth, true);
  std::cout << "  " << estimate.size() << " posed frames: ATE SE(3) " << ate_se3_m << " m, Sim(3) "
            << ate_sim3_m << " m\n";
  EXPECT_LE(ate_se3_m, 0.04);
  EXPECT_LE(ate_sim3_m, 0.02);
}

}  // namespace
}  // namespace viosfm

// The VIO on the first 200 frames (11 s) of the real handheld RealSense
// recording in ../shared/data/realsense_room_30s (see its README): weak
// texture, auto exposure, motion blur, images about 47 ms late against the
// IMU with no offset in the calibration, and an IMU noise file that is far
// off. What the run must get right without ground truth: the time offset,
// a prompt start, and no failure.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <unordered_map>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/euroc.h"
#include "viosfm/util/testing.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {
namespace {

// The recording's camera-IMU time offset (t_imu = t_cam + offset), from a
// separate program that shares no code with viosfm (OpenCV LK tracks,
// frame-to-frame rotation by RANSAC on the bearing vectors with a
// rotation-only model, gyro integrated over the shifted frame intervals
// with the static bias removed, body_from_cam from cam0/sensor.yaml):
//  - the offset that best aligns the gyro's and the images' rotations:
//    -45 ms over the first 190 frames, -47.5 ms over all 545 (-43.5 and
//    -46.5 ms with a 1.5 px instead of 3 px inlier threshold);
//  - the lag that best correlates the gyro's and the images' angular rate
//    vectors: -43 ms over the first 190 frames, -45.5 ms over all 545.
// So -42 to -47.5 ms; the test accepts [-50, -41] ms. The calibration's 0 ms
// (or a wrong sign) explains the images far worse: the rotation residual
// there is 3 to 4 times that at -45 ms.
constexpr double kOffsetMinMs = -50.0;
constexpr double kOffsetMaxMs = -41.0;

// The estimate waits for 90 degrees of gyro rotation (TimeOffsetOptions
// default), which this recording reaches at its 183rd frame (10 s): fewer
// frames leave the calibration's offset, and the VIO then starts late and
// loses landmarks for seconds.
constexpr int kNumFrames = 200;

TEST(RealSenseReplay, FirstElevenSeconds) {
  VIOSFM_REQUIRE_DATASET(root, "realsense_room_30s");
  EurocReadOptions read_options;
  read_options.require_imu = true;
  const Sequence sequence = ReadEurocDataset(root, read_options);
  ASSERT_GE(sequence.images.size(), static_cast<size_t>(kNumFrames));
  ASSERT_EQ(sequence.rig.cam_time_offset_ns, 0);  // the calibration states none

  VioOptions options;  // the defaults of `viosfm vio`
  options.show_progress = false;
  options.max_frames = kNumFrames;
  const VioResult result = RunVio(sequence, options);
  const VioSummary& summary = result.summary;
  std::cout << "RealSense room, first " << kNumFrames << " frames: " << summary.message << "\n  "
            << summary.time_offset.message << "\n  " << summary.imu_noise.message << "\n  tracking "
            << summary.status_counts[static_cast<int>(VioStatus::kTracking)] << ", initializing "
            << summary.status_counts[static_cast<int>(VioStatus::kInitializing)] << ", imu_only "
            << summary.status_counts[static_cast<int>(VioStatus::kImuOnly)] << ", lost "
            << summary.status_counts[static_cast<int>(VioStatus::kLost)] << "; CPU "
            << summary.cpu_seconds << " s\n";

  // The time offset.
  EXPECT_TRUE(summary.time_offset.estimated) << summary.time_offset.message;
  const double offset_ms = NsToSeconds(summary.time_offset.offset_ns) * 1e3;
  EXPECT_GE(offset_ms, kOffsetMinMs) << summary.time_offset.message;
  EXPECT_LE(offset_ms, kOffsetMaxMs) << summary.time_offset.message;

  // The IMU starts 1.25 s before the first image; its rate stays below
  // 0.01 rad/s for the first 0.68 s and below 0.05 rad/s until 0.1 s before
  // the first image, then the hand turns (0.2 rad/s 0.2 s after it): a
  // static start that begins with the IMU and ends before the first image.
  const timestamp_ns_t first_image_ns = sequence.images.front().timestamp_ns;
  ASSERT_TRUE(summary.static_init.is_static()) << summary.static_init.message;
  EXPECT_EQ(summary.static_init.start_ns, sequence.imu.front().timestamp_ns);
  EXPECT_LT(summary.static_init.end_ns, first_image_ns + summary.time_offset.offset_ns);
  EXPECT_GT(NsToSeconds(summary.static_init.end_ns - summary.static_init.start_ns), 0.5);
  // The file's accelerometer density (0.18 m/s^2/sqrt(Hz), ten times a
  // consumer MEMS data sheet) is replaced by a far smaller one measured at
  // rest; the gyro figure (3.7e-5, below any MEMS gyro) is raised.
  EXPECT_TRUE(summary.imu_noise.measured) << summary.imu_noise.message;
  EXPECT_LT(summary.imu_noise.used.accel_noise_density,
            0.2 * summary.imu_noise.given.accel_noise_density);
  EXPECT_GT(summary.imu_noise.used.gyro_noise_density, summary.imu_noise.given.gyro_noise_density);

  // Visual-inertial tracking within 2 s of the first image, no failure, one
  // segment, a pose for every frame.
  ASSERT_TRUE(summary.visual_initialized) << summary.message;
  EXPECT_LT(NsToSeconds(summary.first_tracking_ns - first_image_ns), 2.0) << summary.message;
  EXPECT_EQ(summary.num_resets, 0);
  EXPECT_TRUE(summary.resets.empty());
  EXPECT_EQ(summary.status_counts[static_cast<int>(VioStatus::kLost)], 0u);
  EXPECT_EQ(summary.num_segments, 1);
  ASSERT_EQ(result.frames.size(), static_cast<size_t>(kNumFrames));
  size_t tracking_after_start = 0;
  size_t frames_after_start = 0;
  for (size_t k = 0; k < result.frames.size(); ++k) {
    const VioFrameResult& frame = result.frames[k];
    EXPECT_EQ(frame.timestamp_ns, sequence.images[k].timestamp_ns);
    EXPECT_TRUE(frame.has_pose) << "frame " << k;
    EXPECT_EQ(frame.segment, 0) << "frame " << k;
    EXPECT_TRUE(frame.state.world_from_body.translation.allFinite()) << "frame " << k;
    EXPECT_TRUE(frame.state.velocity_in_world.allFinite()) << "frame " << k;
    if (frame.timestamp_ns >= summary.first_tracking_ns) {
      ++frames_after_start;
      if (frame.status == VioStatus::kTracking) ++tracking_after_start;
    }
  }
  // The newest pose's marginal covariance ([rotation in the world frame,
  // position]) on the tracking frames: symmetric positive definite; roll and
  // pitch, observable through gravity, within a degree; yaw and position,
  // unobservable, never better known than the static start's prior fixed
  // them (the images and the IMU carry no information about them).
  const InitialStateSigmas& gauge = options.static_start_sigmas;
  double min_yaw_sigma = 1e9;
  double min_position_sigma = 1e9;
  for (const VioFrameResult& frame : result.frames) {
    if (frame.status != VioStatus::kTracking) continue;
    const Eigen::Matrix<double, 6, 6>& covariance = frame.pose_covariance;
    ASSERT_TRUE(covariance.allFinite());
    EXPECT_LT((covariance - covariance.transpose()).cwiseAbs().maxCoeff(),
              1e-9 * covariance.diagonal().maxCoeff());
    using Matrix6d = Eigen::Matrix<double, 6, 6>;
    const double smallest = Eigen::SelfAdjointEigenSolver<Matrix6d>(covariance).eigenvalues()(0);
    EXPECT_GT(smallest, 0.0);
    EXPECT_LT(std::sqrt(covariance(0, 0)), M_PI / 180.0);
    EXPECT_LT(std::sqrt(covariance(1, 1)), M_PI / 180.0);
    min_yaw_sigma = std::min(min_yaw_sigma, std::sqrt(covariance(2, 2)));
    for (int i = 3; i < 6; ++i) {
      min_position_sigma = std::min(min_position_sigma, std::sqrt(covariance(i, i)));
    }
  }
  std::cout << "  smallest sigma of a tracking frame: yaw " << min_yaw_sigma << " rad (prior "
            << gauge.yaw_rad << "), position " << min_position_sigma << " m (prior "
            << gauge.position_m << ")\n";
  EXPECT_GE(min_yaw_sigma, gauge.yaw_rad);
  EXPECT_GE(min_position_sigma, gauge.position_m);

  // Once started, the images carry the estimate: at most a tenth of the
  // frames on the IMU alone.
  EXPECT_GE(tracking_after_start * 10, frames_after_start * 9)
      << tracking_after_start << " of " << frames_after_start << " frames tracking";
}

// The same recording from 10 s after its first image on (334 frames, 20 s):
// a start in motion, as a recording cut from a longer walk begins. No
// static interval, so the visual-inertial initialisation starts the VIO, and
// in the 10 s the time-offset estimate may wait, the hand turns 89.9 degrees,
// short of the 90 the estimate waits for. Before the estimate was made from
// 30 degrees on, the calibration's 0 ms stood and 111 of the frames were
// carried by the IMU alone (160 and a reset from 5 s on).
TEST(RealSenseReplay, StartingInMotion) {
  VIOSFM_REQUIRE_DATASET(root, "realsense_room_30s");
  EurocReadOptions read_options;
  read_options.require_imu = true;
  Sequence sequence = ReadEurocDataset(root, read_options);
  // The whole recording, which starts at rest, is the reference for the scale.
  VioOptions whole_options;
  whole_options.show_progress = false;
  const VioResult whole = RunVio(sequence, whole_options);
  const timestamp_ns_t start_ns = sequence.images.front().timestamp_ns + SecondsToNs(10.0);
  std::erase_if(sequence.images,
                [&](const SequenceImage& image) { return image.timestamp_ns < start_ns; });
  std::erase_if(sequence.imu, [&](const ImuSample& sample) {
    return sample.timestamp_ns < start_ns - SecondsToNs(0.05);
  });
  ASSERT_GE(sequence.images.size(), 300u);

  VioOptions options;  // the defaults of `viosfm vio`
  options.show_progress = false;
  const VioResult result = RunVio(sequence, options);
  const VioSummary& summary = result.summary;
  const auto count = [&](VioStatus status) {
    return summary.status_counts[static_cast<int>(status)];
  };
  std::cout << "RealSense room from 10 s on, " << sequence.images.size()
            << " frames: " << summary.message << "\n  " << summary.time_offset.message
            << "\n  tracking " << count(VioStatus::kTracking) << ", initializing "
            << count(VioStatus::kInitializing) << ", imu_only " << count(VioStatus::kImuOnly)
            << ", lost " << count(VioStatus::kLost) << ", without a pose "
            << summary.num_frames_without_pose << "; CPU " << summary.cpu_seconds << " s\n";

  EXPECT_FALSE(summary.static_init.is_static()) << summary.static_init.message;
  // The offset: estimated, near the whole recording's. Over these 90
  // degrees it comes out at -53 ms with a readout of 24 ms (the whole
  // recording: -47 ms, 21 ms; offset and readout trade against each other
  // over short stretches), against the independent -43 to -47.5 ms as a
  // global shutter.
  EXPECT_TRUE(summary.time_offset.estimated) << summary.time_offset.message;
  const double offset_ms = NsToSeconds(summary.time_offset.offset_ns) * 1e3;
  EXPECT_GE(offset_ms, -60.0) << summary.time_offset.message;
  EXPECT_LE(offset_ms, kOffsetMaxMs) << summary.time_offset.message;

  // Tracking within 2 s, no failure, one segment, nothing on the IMU alone.
  ASSERT_TRUE(summary.visual_initialized) << summary.message;
  EXPECT_LT(NsToSeconds(summary.first_tracking_ns - start_ns), 2.0) << summary.message;
  EXPECT_EQ(summary.num_resets, 0);
  EXPECT_EQ(count(VioStatus::kLost), 0u);
  EXPECT_EQ(count(VioStatus::kImuOnly), 0u);
  EXPECT_EQ(summary.num_segments, 1);
  // Every frame has a pose: those before the initialisation (14 here) are
  // posed once it succeeds, by its keyframes' states and PnP on its
  // landmarks (VioOptions::pose_moving_start).
  for (const VioFrameResult& frame : result.frames) EXPECT_TRUE(frame.has_pose);
  EXPECT_EQ(summary.num_frames_without_pose, 0u);
  EXPECT_GE(summary.num_moving_start_keyframes + summary.num_moving_start_pnp, 10u);
  EXPECT_EQ(result.BodyTrajectory().poses.size(), result.frames.size());

  // The scale: the positions of the frames both runs track, aligned by a
  // similarity, agree within 10 % in scale (measured 0.98) and 3 cm RMS
  // (9 mm). Without a static start the noise check bounds the file's
  // accelerometer density (0.18, clamped to 0.05) by the quietest half
  // second of the stream (0.008); at 0.05 the IMU weighed too little
  // against the images, and this run came out 1.83 times too small.
  std::unordered_map<timestamp_ns_t, Eigen::Vector3d> whole_positions;
  for (const VioFrameResult& frame : whole.frames) {
    if (frame.status == VioStatus::kTracking) {
      whole_positions.emplace(frame.timestamp_ns, frame.state.world_from_body.translation);
    }
  }
  std::vector<Eigen::Vector3d> cut_points;
  std::vector<Eigen::Vector3d> whole_points;
  for (const VioFrameResult& frame : result.frames) {
    const auto found = whole_positions.find(frame.timestamp_ns);
    if (frame.status != VioStatus::kTracking || found == whole_positions.end()) continue;
    cut_points.push_back(frame.state.world_from_body.translation);
    whole_points.push_back(found->second);
  }
  ASSERT_GE(cut_points.size(), 250u);
  const std::optional<Sim3d> whole_from_cut = AlignPointsUmeyama(cut_points, whole_points, true);
  ASSERT_TRUE(whole_from_cut);
  double sum = 0.0;
  for (size_t k = 0; k < cut_points.size(); ++k) {
    sum += ((*whole_from_cut) * cut_points[k] - whole_points[k]).squaredNorm();
  }
  const double rmse_m = std::sqrt(sum / static_cast<double>(cut_points.size()));
  std::cout << "  against the whole recording's VIO (" << cut_points.size() << " frames): scale "
            << whole_from_cut->scale << ", RMSE " << rmse_m << " m\n";
  EXPECT_NEAR(whole_from_cut->scale, 1.0, 0.1);
  EXPECT_LT(rmse_m, 0.03);
}

}  // namespace
}  // namespace viosfm

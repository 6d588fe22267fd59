// The VIO's restart after a loss, on a rendered sequence whose camera goes
// black for a second: the window loses its landmarks, is reset, and starts
// again by visual-inertial re-initialisation once the images return.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"
#include "viosfm/vio/odometry.h"

namespace viosfm {
namespace {

// RMS position error (m) of the frames [begin, end) with status kTracking
// after `alignment` (estimate to truth), and how many there are.
std::pair<double, int> TrackingError(const VioResult& result, const SimulatedSequence& simulated,
                                     size_t begin, size_t end, const Sim3d& alignment) {
  double sum = 0.0;
  int count = 0;
  for (size_t k = begin; k < end; ++k) {
    const VioFrameResult& frame = result.frames[k];
    if (frame.status != VioStatus::kTracking) continue;
    sum += (alignment * frame.state.world_from_body.translation -
            simulated.motion.PositionInWorld(frame.timestamp_ns))
               .squaredNorm();
    ++count;
  }
  return {count > 0 ? std::sqrt(sum / count) : 0.0, count};
}

// SE(3) alignment of the kTracking frames [begin, end) to the truth.
std::optional<Sim3d> AlignTracking(const VioResult& result, const SimulatedSequence& simulated,
                                   size_t begin, size_t end) {
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> truth;
  for (size_t k = begin; k < end; ++k) {
    const VioFrameResult& frame = result.frames[k];
    if (frame.status != VioStatus::kTracking) continue;
    estimated.push_back(frame.state.world_from_body.translation);
    truth.push_back(simulated.motion.PositionInWorld(frame.timestamp_ns));
  }
  if (estimated.size() < 3) return std::nullopt;
  return AlignPointsUmeyama(estimated, truth, false);
}

// A rendered room sequence at half resolution (as odometry_test's), 13 s
// with a 2 s static start, written to a scratch folder.
struct RenderedRoom {
  SimulationOptions simulation;
  SimulatedSequence simulated;
  Sequence sequence;
};

RenderedRoom RenderRoom(const std::string& name) {
  RenderedRoom room;
  SimulationOptions& simulation = room.simulation;
  simulation.scenario = "room";
  simulation.duration_s = 13.0;
  simulation.static_start_s = 2.0;
  simulation.camera_rate_hz = 12.0;
  simulation.seed = 3;
  simulation.num_threads = 2;
  simulation.texels_per_metre = 64.0;
  Camera camera = SimulationOptions::DefaultCamera();
  camera.width = 376;
  camera.height = 240;
  camera.params[0] *= 0.5;
  camera.params[1] *= 0.5;
  camera.params[2] = (camera.params[2] + 0.5) * 0.5 - 0.5;
  camera.params[3] = (camera.params[3] + 0.5) * 0.5 - 0.5;
  simulation.camera = camera;
  room.simulated = SimulateSequence(simulation);
  const std::filesystem::path folder = testing::MakeScratchFolder(name);
  WriteSimulatedSequence(folder, room.simulated, simulation);
  room.sequence = ReadEurocDataset(folder);
  return room;
}

VioOptions TestOptions() {
  VioOptions options;
  options.show_progress = false;
  options.tracker.min_distance_px = 15.0;
  options.tracker.max_num_features = 120;
  return options;
}

TEST(RunVio, RestartAfterAnImageBlackout) {
  const RenderedRoom room = RenderRoom("vio_blackout");
  const SimulatedSequence& simulated = room.simulated;
  const Sequence& sequence = room.sequence;
  const Camera& camera = room.simulation.camera;
  ASSERT_EQ(sequence.images.size(), simulated.sequence.images.size());

  // The camera goes black from 8 to 9 s after the first image (the start-up
  // time offset estimate is made before).
  const timestamp_ns_t first_ns = sequence.images.front().timestamp_ns;
  const timestamp_ns_t blackout_begin_ns = first_ns + SecondsToNs(8.0);
  const timestamp_ns_t blackout_end_ns = first_ns + SecondsToNs(9.0);
  size_t first_black = sequence.images.size();
  size_t end_black = 0;
  const GreyImage black(camera.width, camera.height, 0);
  for (size_t k = 0; k < sequence.images.size(); ++k) {
    const SequenceImage& image = sequence.images[k];
    if (image.timestamp_ns < blackout_begin_ns || image.timestamp_ns >= blackout_end_ns) continue;
    WriteGreyPng(image.path, black);
    first_black = std::min(first_black, k);
    end_black = k + 1;
  }
  ASSERT_LT(first_black, end_black);

  VioOptions options = TestOptions();
  // Lost after 0.5 s without landmarks (default 3 s), inside the blackout.
  options.window.max_imu_only_s = 0.5;
  const VioResult result = RunVio(sequence, options);
  const VioSummary& summary = result.summary;
  std::cout << summary.message << "\n";
  for (const VioReset& reset : summary.resets) {
    std::cout << "reset at " << NsToSeconds(reset.timestamp_ns - first_ns)
              << " s: " << reset.message << "; relocalized " << reset.relocalized << ", "
              << reset.num_map_points << " map points\n";
  }
  // One trajectory: a state for every image, in order.
  ASSERT_EQ(result.frames.size(), sequence.images.size());
  ASSERT_TRUE(summary.visual_initialized) << summary.message;
  ASSERT_EQ(summary.num_resets, 1) << summary.message;
  ASSERT_EQ(summary.resets.size(), 1u);
  const VioReset& reset = summary.resets.front();
  EXPECT_GE(reset.timestamp_ns, blackout_begin_ns);
  EXPECT_LT(reset.timestamp_ns, blackout_end_ns);
  // No corner survives a black image, so none of the kept map points can be
  // seen again: the restart is joined by the IMU alone and starts a segment.
  EXPECT_FALSE(reset.relocalized);
  EXPECT_EQ(reset.num_map_points, 0);
  EXPECT_EQ(summary.num_segments, 2);

  size_t lost = result.frames.size();
  size_t tracking_again = result.frames.size();
  for (size_t k = 0; k < result.frames.size(); ++k) {
    const VioFrameResult& frame = result.frames[k];
    EXPECT_EQ(frame.timestamp_ns, sequence.images[k].timestamp_ns);
    EXPECT_TRUE(frame.has_pose) << "frame " << k;
    EXPECT_TRUE(frame.state.world_from_body.translation.allFinite()) << "frame " << k;
    if (frame.status == VioStatus::kLost) {
      EXPECT_EQ(lost, result.frames.size()) << "a second lost frame " << k;
      lost = k;
      EXPECT_EQ(frame.timestamp_ns, reset.timestamp_ns);
    }
    if (lost < k && frame.status == VioStatus::kTracking &&
        tracking_again == result.frames.size()) {
      tracking_again = k;
    }
    EXPECT_EQ(frame.segment, lost <= k ? 1 : 0) << "frame " << k;
  }
  ASSERT_LT(lost, result.frames.size());
  ASSERT_LT(tracking_again, result.frames.size()) << "never tracking again after the reset";
  const double back_after_s =
      NsToSeconds(result.frames[tracking_again].timestamp_ns - blackout_end_ns);
  EXPECT_LT(back_after_s, 2.5);

  // Each segment is accurate on its own; the second, placed where the IMU
  // carried the first, stays close to it.
  const std::optional<Sim3d> first_alignment = AlignTracking(result, simulated, 0, lost);
  const std::optional<Sim3d> second_alignment =
      AlignTracking(result, simulated, lost, result.frames.size());
  ASSERT_TRUE(first_alignment && second_alignment);
  const auto [first_error, first_count] =
      TrackingError(result, simulated, 0, lost, *first_alignment);
  const auto [second_error, second_count] =
      TrackingError(result, simulated, lost, result.frames.size(), *second_alignment);
  const auto [joined_error, joined_count] =
      TrackingError(result, simulated, lost, result.frames.size(), *first_alignment);
  std::cout << "blackout " << NsToSeconds(blackout_begin_ns - first_ns) << " to "
            << NsToSeconds(blackout_end_ns - first_ns) << " s: lost at "
            << NsToSeconds(reset.timestamp_ns - first_ns) << " s, tracking again " << back_after_s
            << " s after the images return; RMS error " << first_error << " m before ("
            << first_count << " frames), " << second_error << " m after (" << second_count
            << " frames), " << joined_error << " m after in the first segment's alignment\n";
  EXPECT_LT(first_error, 0.1);
  EXPECT_LT(second_error, 0.1);
  // The second segment's world is placed where the IMU carried the last good
  // state across the frames without landmarks (1.8 s from the last tracking
  // frame to the restart): an acceleration error of 0.1 m/s^2 (gravity 0.6
  // degrees off) alone moves it by 0.16 m.
  EXPECT_LT(joined_error, 0.25);
}

// Corners of a textured room seen along a walk, without rendering: points on
// the walls, floor and ceiling of a 10 x 10 x 3 m room, projected through the
// simulator's default camera with 0.5 px noise; a point keeps its track id
// whenever it is seen (as if every corner were re-identified). The walk
// starts with 2 s at rest; the IMU has EuRoC noise.
struct SyntheticRoom {
  BodyTrajectory trajectory;
  SensorRig rig;
  std::vector<ImuSample> imu;
  std::vector<FrameFeatures> frames;
};

SyntheticRoom MakeSyntheticRoom(double duration_s, double camera_rate_hz, uint64_t seed) {
  SyntheticRoom room;
  WalkOptions walk;
  walk.duration_s = duration_s;
  walk.static_start_s = 2.0;
  walk.speed_mps = 0.6;
  walk.seed = seed;
  room.trajectory = GenerateWalk(walk);
  room.rig.camera = SimulationOptions::DefaultCamera();
  room.rig.body_from_cam = SimulationOptions::DefaultBodyFromCam();
  room.rig.camera_rate_hz = camera_rate_hz;
  ImuSynthesisOptions imu_options;
  imu_options.seed = seed + 1;
  room.rig.imu_noise = imu_options.noise;
  room.imu = SynthesizeImu(room.trajectory, room.trajectory.start_ns(), room.trajectory.end_ns(),
                           imu_options)
                 .samples;

  Random random(seed + 2);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 1500; ++i) {
    const double a = random.Uniform(-5.0, 5.0);
    const double b = random.Uniform(-5.0, 5.0);
    const double h = random.Uniform(0.0, 3.0);
    switch (i % 6) {
      case 0: points.emplace_back(5.0, a, h); break;
      case 1: points.emplace_back(-5.0, a, h); break;
      case 2: points.emplace_back(a, 5.0, h); break;
      case 3: points.emplace_back(a, -5.0, h); break;
      case 4: points.emplace_back(a, b, 0.0); break;
      default: points.emplace_back(a, b, 3.0); break;
    }
  }
  const std::vector<double>& params = room.rig.camera.params;
  const double fx = params[0];
  const double fy = params[1];
  const double cx = params[2];
  const double cy = params[3];
  const double width = room.rig.camera.width;
  const double height = room.rig.camera.height;
  for (timestamp_ns_t t = room.trajectory.start_ns();
       t + SecondsToNs(0.05) < room.trajectory.end_ns(); t += SecondsToNs(1.0 / camera_rate_hz)) {
    FrameFeatures frame;
    frame.timestamp_ns = t;
    const Rigid3d cam_from_world =
        (room.trajectory.WorldFromBody(t) * room.rig.body_from_cam).Inverse();
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d in_cam = cam_from_world * points[i];
      if (in_cam.z() < 0.3) continue;
      Eigen::Vector2d pixel(fx * in_cam.x() / in_cam.z() + cx, fy * in_cam.y() / in_cam.z() + cy);
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > width - 1 || pixel.y() > height - 1) {
        continue;
      }
      pixel += Eigen::Vector2d(random.Normal(0.0, 0.5), random.Normal(0.0, 0.5));
      FeatureObservation observation;
      observation.track_id = i;
      observation.pixel = pixel;
      observation.normalized = Eigen::Vector2d((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
      frame.observations.push_back(observation);
    }
    room.frames.push_back(std::move(frame));
  }
  return room;
}

// RMS position error (m) of the kTracking results after one SE(3)
// alignment of them all to the truth, and of those from `from_ns` on.
std::pair<double, double> OneFrameErrors(const std::vector<VioFrameResult>& results,
                                         const BodyTrajectory& truth, timestamp_ns_t from_ns) {
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> true_positions;
  std::vector<bool> after;
  for (const VioFrameResult& result : results) {
    if (result.status != VioStatus::kTracking) continue;
    estimated.push_back(result.state.world_from_body.translation);
    true_positions.push_back(truth.PositionInWorld(result.timestamp_ns));
    after.push_back(result.timestamp_ns >= from_ns);
  }
  const std::optional<Sim3d> alignment = AlignPointsUmeyama(estimated, true_positions, false);
  if (!alignment) return {1e9, 1e9};
  double sum = 0.0;
  double after_sum = 0.0;
  int after_count = 0;
  for (size_t k = 0; k < estimated.size(); ++k) {
    const double squared = ((*alignment) * estimated[k] - true_positions[k]).squaredNorm();
    sum += squared;
    if (after[k]) {
      after_sum += squared;
      ++after_count;
    }
  }
  return {std::sqrt(sum / estimated.size()),
          after_count > 0 ? std::sqrt(after_sum / after_count) : 1e9};
}

// Every corner vanishes for 0.8 s (3.0 to 3.8 s, while the camera keeps
// looking at the same walls, whose corners it sees until after the
// re-localisation window). When they come back with their old track ids, the
// restarted window finds the map kept at the reset and re-localises against
// it for relocalization_window_s after the restart; with new ids (what a
// tracker that lost them gives) it cannot, and the restart is joined by the
// IMU alone. Either way every frame has a pose and the run is one
// trajectory in one frame (the IMU carries the state across the short gap
// to within a few centimetres).
TEST(VisualInertialOdometry, RelocalisesAfterACornerBlackout) {
  const SyntheticRoom room = MakeSyntheticRoom(8.5, 15.0, 5);
  const timestamp_ns_t start_ns = room.trajectory.start_ns();
  const timestamp_ns_t blackout_begin_ns = start_ns + SecondsToNs(3.0);
  const timestamp_ns_t blackout_end_ns = start_ns + SecondsToNs(3.8);
  VioOptions options;
  options.show_progress = false;
  // Lost after 0.5 s without landmarks (default 3 s), inside the blackout.
  options.window.max_imu_only_s = 0.5;
  for (const bool same_ids : {true, false}) {
    SCOPED_TRACE(same_ids ? "same track ids" : "new track ids");
    VisualInertialOdometry vio(room.rig, room.imu, room.frames.front().timestamp_ns,
                               room.frames.back().timestamp_ns, options);
    std::vector<VioFrameResult> results;
    for (FrameFeatures frame : room.frames) {
      if (frame.timestamp_ns >= blackout_begin_ns && frame.timestamp_ns < blackout_end_ns) {
        frame.observations.clear();
      } else if (!same_ids && frame.timestamp_ns >= blackout_end_ns) {
        for (FeatureObservation& observation : frame.observations) {
          observation.track_id += 100000;
        }
      }
      results.push_back(vio.ProcessFrame(frame));
    }
    const VioSummary& summary = vio.summary();
    ASSERT_EQ(summary.num_resets, 1) << summary.message;
    ASSERT_EQ(summary.resets.size(), 1u);
    const VioReset& reset = summary.resets.front();
    EXPECT_GE(reset.timestamp_ns, blackout_begin_ns);
    EXPECT_LT(reset.timestamp_ns, blackout_end_ns);

    // The restart: the first frame the re-initialised window estimates
    // (status kInitializing with a pose after the lost frame), and the
    // frames that saw map points of the previous window.
    timestamp_ns_t restart_ns = -1;
    timestamp_ns_t last_map_ns = -1;
    bool after_lost = false;
    for (const VioFrameResult& result : results) {
      EXPECT_TRUE(result.has_pose);
      EXPECT_TRUE(result.state.world_from_body.translation.allFinite());
      if (result.status == VioStatus::kLost) after_lost = true;
      if (after_lost && restart_ns < 0 && result.status == VioStatus::kInitializing) {
        restart_ns = result.timestamp_ns;
      }
      if (result.num_map_points > 0) last_map_ns = result.timestamp_ns;
    }
    ASSERT_GT(restart_ns, 0) << "never re-initialised";
    const auto [rms, rms_after] = OneFrameErrors(results, room.trajectory, blackout_end_ns);
    std::cout << (same_ids ? "same" : "new") << " track ids: reset at "
              << NsToSeconds(reset.timestamp_ns - start_ns) << " s, restart at "
              << NsToSeconds(restart_ns - start_ns) << " s, relocalized " << reset.relocalized
              << " (" << reset.num_map_points << " map point observations, the last at "
              << (last_map_ns > 0 ? NsToSeconds(last_map_ns - start_ns) : 0.0)
              << " s); RMS error in one frame " << rms << " m, after the blackout " << rms_after
              << " m\n";
    // The re-initialisation needs its keyframes' parallax: well within 2 s.
    EXPECT_LT(NsToSeconds(restart_ns - blackout_end_ns), 2.0);
    EXPECT_LT(rms, 0.05);
    EXPECT_LT(rms_after, 0.05);
    if (same_ids) {
      EXPECT_TRUE(reset.relocalized);
      EXPECT_GE(reset.num_map_points, options.window.min_relocalization_points);
      // The map ties the restarted window's frames for
      // relocalization_window_s after the restart (minus a frame), not
      // after the first of the re-initialisation's keyframes.
      EXPECT_GE(NsToSeconds(last_map_ns - restart_ns),
                options.window.relocalization_window_s - 1.0 / room.rig.camera_rate_hz - 1e-6);
    } else {
      EXPECT_FALSE(reset.relocalized);
      EXPECT_EQ(reset.num_map_points, 0);
      EXPECT_LT(last_map_ns, 0);
    }
  }
}

}  // namespace
}  // namespace viosfm

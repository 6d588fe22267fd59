#include "viosfm/vio/odometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

int CountLines(const std::filesystem::path& path) {
  std::ifstream stream(path);
  int lines = 0;
  std::string line;
  while (std::getline(stream, line)) ++lines;
  return lines;
}

TEST(VioOptions, ValidateNamesTheBadField) {
  VioOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.window.max_num_iterations = 0;
  EXPECT_NE(options.Validate().find("window.max_num_iterations"), std::string::npos);
  options = VioOptions();
  options.restart_sigmas.velocity_mps = 0.0;
  EXPECT_NE(options.Validate().find("restart_sigmas"), std::string::npos);
}

// A short rendered room sequence (half-resolution camera to keep it fast):
// static start, then tracking with a bounded error.
// A small rendered room (376 x 240 at 12 Hz), written and read back as a
// dataset in `folder_name`.
struct SmallRoom {
  SimulationOptions simulation;
  SimulatedSequence simulated;
  std::filesystem::path folder;
  Sequence sequence;
};
SmallRoom SimulateSmallRoom(double duration_s, double static_start_s, uint64_t seed,
                            const std::string& folder_name) {
  SmallRoom room;
  SimulationOptions& simulation = room.simulation;
  simulation.scenario = "room";
  simulation.duration_s = duration_s;
  simulation.static_start_s = static_start_s;
  simulation.camera_rate_hz = 12.0;
  simulation.seed = seed;
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
  room.folder = testing::MakeScratchFolder(folder_name);
  WriteSimulatedSequence(room.folder, room.simulated, simulation);
  room.sequence = ReadEurocDataset(room.folder);
  return room;
}

// The VIO options of these rendered rooms: fewer, sparser corners.
VioOptions SmallRoomVioOptions() {
  VioOptions options;
  options.show_progress = false;
  options.tracker.min_distance_px = 15.0;
  options.tracker.max_num_features = 120;
  return options;
}

TEST(RunVio, RenderedRoomSequence) {
  const SmallRoom room = SimulateSmallRoom(7.0, 2.0, 3, "vio_room");
  const SimulationOptions& simulation = room.simulation;
  const SimulatedSequence& simulated = room.simulated;
  const std::filesystem::path& folder = room.folder;
  const Sequence& sequence = room.sequence;
  ASSERT_EQ(sequence.images.size(), simulated.sequence.images.size());

  const VioOptions options = SmallRoomVioOptions();
  const VioResult result = RunVio(sequence, options);
  ASSERT_EQ(result.frames.size(), sequence.images.size());

  const timestamp_ns_t motion_start_ns =
      sequence.images.front().timestamp_ns + SecondsToNs(simulation.static_start_s);
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> truth;
  size_t moving_frames = 0;
  for (const VioFrameResult& frame : result.frames) {
    ASSERT_TRUE(frame.state.world_from_body.translation.allFinite());
    ASSERT_TRUE(frame.state.velocity_in_world.allFinite());
    EXPECT_NE(frame.status, VioStatus::kLost);
    if (frame.timestamp_ns < motion_start_ns - SecondsToNs(0.6)) {
      EXPECT_EQ(frame.status, VioStatus::kInitializing);
    } else {
      ++moving_frames;
    }
    if (frame.status == VioStatus::kTracking) {
      estimated.push_back(frame.state.world_from_body.translation);
      truth.push_back(simulated.motion.PositionInWorld(frame.timestamp_ns));
    }
  }
  const VioSummary& summary = result.summary;
  EXPECT_TRUE(summary.static_init.is_static());
  ASSERT_TRUE(summary.visual_initialized) << summary.message;
  const double init_delay_s = NsToSeconds(summary.first_tracking_ns - motion_start_ns);
  EXPECT_LT(init_delay_s, 3.0);
  EXPECT_GT(estimated.size(), moving_frames * 6 / 10);
  const std::optional<Sim3d> se3 = AlignPointsUmeyama(estimated, truth, false);
  const std::optional<Sim3d> sim3 = AlignPointsUmeyama(estimated, truth, true);
  ASSERT_TRUE(se3 && sim3);
  double sum = 0.0;
  for (size_t k = 0; k < estimated.size(); ++k) {
    sum += ((*se3) * estimated[k] - truth[k]).squaredNorm();
  }
  const double ate_m = std::sqrt(sum / static_cast<double>(estimated.size()));
  std::cout << "rendered room " << simulation.duration_s << " s: " << result.frames.size()
            << " frames, " << estimated.size() << " tracking, init " << init_delay_s
            << " s after motion onset, ATE SE(3) " << ate_m << " m, Sim(3) scale " << sim3->scale
            << "; " << summary.message << "\n";
  EXPECT_LT(ate_m, 0.10);
  EXPECT_NEAR(sim3->scale, 1.0, 0.1);

  // Outputs: one row per frame.
  const std::filesystem::path out = folder / "vio_out";
  WriteVioResult(out, result);
  EXPECT_EQ(CountLines(out / "states.csv"), static_cast<int>(result.frames.size()) + 1);
  EXPECT_EQ(ReadTumTrajectory(out / "trajectory_body.tum").size(), result.frames.size());
  EXPECT_EQ(ReadTumTrajectory(out / "trajectory_cam.tum").size(), result.frames.size());
}

// A start in motion: the frames before the visual-inertial initialisation
// are posed once it succeeds (its keyframes by its states, the others by
// PnP on its landmarks or, near a keyframe, the IMU), within a few
// centimetres of the truth once the trajectory is aligned on the tracking
// frames, as the tracking frames themselves are; with the option off they
// have no pose and are left out of the trajectory.
TEST(RunVio, MovingStartFramesArePosedOnceInitialised) {
  const SmallRoom room = SimulateSmallRoom(6.0, 0.0, 5, "vio_moving_start");
  const VioResult result = RunVio(room.sequence, SmallRoomVioOptions());
  const VioSummary& summary = result.summary;
  ASSERT_FALSE(summary.static_init.is_static()) << summary.static_init.message;
  ASSERT_TRUE(summary.visual_initialized) << summary.message;
  std::cout << "moving start: " << summary.message << "\n";
  const size_t posed_before = summary.num_moving_start_keyframes + summary.num_moving_start_pnp +
                              summary.num_moving_start_imu;
  EXPECT_GE(posed_before, 5u);
  EXPECT_EQ(summary.num_frames_without_pose, 0u);

  // Align on the tracking frames (SE(3): the VIO is metric), then compare.
  std::vector<Eigen::Vector3d> estimated;
  std::vector<Eigen::Vector3d> truth;
  for (const VioFrameResult& frame : result.frames) {
    ASSERT_TRUE(frame.has_pose);
    if (frame.status != VioStatus::kTracking) continue;
    estimated.push_back(frame.state.world_from_body.translation);
    truth.push_back(room.simulated.motion.PositionInWorld(frame.timestamp_ns));
  }
  const std::optional<Sim3d> se3 = AlignPointsUmeyama(estimated, truth, false);
  ASSERT_TRUE(se3);
  const auto rmse = [&](VioStatus status) {
    double sum = 0.0;
    int count = 0;
    for (const VioFrameResult& frame : result.frames) {
      if (frame.status != status) continue;
      sum += ((*se3) * frame.state.world_from_body.translation -
              room.simulated.motion.PositionInWorld(frame.timestamp_ns))
                 .squaredNorm();
      ++count;
    }
    return std::sqrt(sum / std::max(count, 1));
  };
  const double tracking_m = rmse(VioStatus::kTracking);
  const double before_m = rmse(VioStatus::kInitializing);
  std::cout << "  position RMSE after SE(3) alignment: tracking frames " << tracking_m << " m, the "
            << posed_before << " frames posed once initialised " << before_m << " m\n";
  EXPECT_LT(tracking_m, 0.05);
  EXPECT_LT(before_m, 0.05);

  // The IMU starting 1 s after the first image: the frames before it are
  // not taken among the initialisation's keyframes (which its IMU could not
  // join, so every attempt failed until they left: tracking 0.92 s after
  // the IMU's start, now 0.50 s; on the real recording from 10 s on with
  // the IMU 1 s late, 7.8 s and now 0.86 s), and are posed by PnP once it
  // succeeds.
  Sequence late_imu = room.sequence;
  const timestamp_ns_t imu_start_ns = late_imu.images.front().timestamp_ns + SecondsToNs(1.0);
  std::erase_if(late_imu.imu,
                [&](const ImuSample& sample) { return sample.timestamp_ns < imu_start_ns; });
  const VioResult late = RunVio(late_imu, SmallRoomVioOptions());
  std::cout << "IMU from 1 s on: " << late.summary.message << "\n";
  ASSERT_TRUE(late.summary.visual_initialized) << late.summary.message;
  EXPECT_LT(NsToSeconds(late.summary.first_tracking_ns - imu_start_ns), 0.7);
  EXPECT_EQ(late.summary.num_frames_without_pose, 0u);
  EXPECT_GT(late.summary.num_moving_start_pnp, 0u);

  VioOptions unposed = SmallRoomVioOptions();
  unposed.pose_moving_start = false;
  const VioResult without = RunVio(room.sequence, unposed);
  EXPECT_GT(without.summary.num_frames_without_pose, 0u);
  EXPECT_EQ(without.BodyTrajectory().poses.size(),
            without.frames.size() - without.summary.num_frames_without_pose);
}

// The first 4.7 s of EuRoC V1_01_easy: the platform stands still. The
// static start gives gravity and the gyro bias; the state is held (no
// drift) and the visual part is reported as not initialised.
// A recording fed to the VIO as a recorder writes it (VioRunner without
// the last frame's stamp): each image once the IMU has passed its stamp by
// a few samples, the IMU in chunks. Every frame is reported settled once,
// never changed after, and the result is RunVio's over the whole recording:
// with a static start the static interval is decided once motion ends it,
// so the window starts as RunVio starts it, pose for pose (measured
// identical); without one (a start in motion) the IMU's noise is checked on
// the samples seen so far, so the poses may differ slightly (measured 0 m).
void ExpectFedLikeRunVio(const SmallRoom& room, double max_difference_m) {
  const VioOptions options = SmallRoomVioOptions();
  const VioResult whole = RunVio(room.sequence, options);
  std::vector<VioFrameResult> reported;
  size_t reports = 0;
  VioRunner runner(room.sequence.rig, options, nullptr, std::nullopt,
                   [&](const VioProgress& progress) {
                     ++reports;
                     ASSERT_GE(progress.num_settled, reported.size());
                     // Frames settled before are as they were.
                     for (size_t k = 0; k < reported.size(); ++k) {
                       ASSERT_EQ((*progress.frames)[k].state.world_from_body.translation,
                                 reported[k].state.world_from_body.translation);
                       ASSERT_EQ((*progress.frames)[k].segment, reported[k].segment);
                     }
                     for (size_t k = reported.size(); k < progress.num_settled; ++k) {
                       reported.push_back((*progress.frames)[k]);
                     }
                   });
  const std::vector<ImuSample>& imu = room.sequence.imu;
  size_t next_sample = 0;
  for (const SequenceImage& image : room.sequence.images) {
    std::vector<ImuSample> chunk;
    while (next_sample < imu.size() &&
           imu[next_sample].timestamp_ns <= image.timestamp_ns + 15'000'000) {
      chunk.push_back(imu[next_sample++]);
    }
    runner.AddImu(chunk);
    runner.AddImage(image);
  }
  runner.AddImu(
      std::vector<ImuSample>(imu.begin() + static_cast<ptrdiff_t>(next_sample), imu.end()));
  const VioResult fed = runner.Finish(room.folder);
  EXPECT_GT(reports, room.sequence.images.size() / 2);
  ASSERT_EQ(fed.frames.size(), whole.frames.size());
  ASSERT_EQ(reported.size(), fed.frames.size());
  double largest_m = 0.0;
  for (size_t k = 0; k < fed.frames.size(); ++k) {
    EXPECT_EQ(fed.frames[k].has_pose, whole.frames[k].has_pose) << k;
    EXPECT_EQ(fed.frames[k].segment, whole.frames[k].segment) << k;
    EXPECT_EQ(reported[k].state.world_from_body.translation,
              fed.frames[k].state.world_from_body.translation)
        << k;
    largest_m = std::max(largest_m, (fed.frames[k].state.world_from_body.translation -
                                     whole.frames[k].state.world_from_body.translation)
                                        .norm());
  }
  std::cout << "fed as recorded: " << fed.frames.size() << " frames, " << reports
            << " reports, largest difference from RunVio " << largest_m << " m\n";
  EXPECT_LE(largest_m, max_difference_m);
  EXPECT_EQ(fed.summary.static_init.is_static(), whole.summary.static_init.is_static());
  EXPECT_EQ(fed.summary.num_resets, whole.summary.num_resets);
}

TEST(VioRunner, ARecordingFedAsItIsMadeGivesRunViosPoses) {
  ExpectFedLikeRunVio(SimulateSmallRoom(7.0, 2.0, 3, "vio_fed_static"), 0.0);
}

TEST(VioRunner, AMovingStartFedAsItIsMade) {
  ExpectFedLikeRunVio(SimulateSmallRoom(6.0, 0.0, 5, "vio_fed_moving"), 0.005);
}

TEST(RunVio, EurocStaticMicro) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence sequence = ReadEurocDataset(root);
  VioOptions options;
  options.show_progress = false;
  const VioResult result = RunVio(sequence, options);
  ASSERT_EQ(result.frames.size(), sequence.images.size());
  const VioSummary& summary = result.summary;
  ASSERT_TRUE(summary.static_init.is_static()) << summary.static_init.message;
  EXPECT_FALSE(summary.visual_initialized);
  EXPECT_NE(summary.message.find("not enough motion"), std::string::npos) << summary.message;
  EXPECT_EQ(summary.status_counts[static_cast<int>(VioStatus::kInitializing)],
            sequence.images.size());

  // Ground truth over the image span: mean gyro bias and up direction.
  const timestamp_ns_t from = sequence.images.front().timestamp_ns;
  const timestamp_ns_t to = sequence.images.back().timestamp_ns;
  Eigen::Vector3d true_gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d true_up = Eigen::Vector3d::Zero();
  int count = 0;
  for (const GroundTruthState& state : sequence.ground_truth) {
    if (state.timestamp_ns < from - 1000 || state.timestamp_ns > to + 1000) continue;
    true_gyro_bias += state.gyro_bias;
    true_up += state.world_from_body.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    ++count;
  }
  ASSERT_GT(count, 90);
  true_gyro_bias /= count;
  true_up.normalize();
  const Eigen::Vector3d up_in_body = -summary.static_init.gravity_in_body.normalized();
  const double up_error_deg = std::acos(std::clamp(up_in_body.dot(true_up), -1.0, 1.0)) * kRadToDeg;
  const double gyro_error = (summary.static_init.gyro_bias - true_gyro_bias).cwiseAbs().maxCoeff();

  double drift_m = 0.0;
  for (const VioFrameResult& frame : result.frames) {
    ASSERT_TRUE(frame.state.world_from_body.translation.allFinite());
    ASSERT_TRUE(frame.state.velocity_in_world.allFinite());
    EXPECT_EQ(frame.status, VioStatus::kInitializing);
    drift_m = std::max(drift_m, (frame.state.world_from_body.translation -
                                 result.frames.front().state.world_from_body.translation)
                                    .norm());
    // The held state is gravity aligned: the body's up is the estimate's.
    const Eigen::Vector3d up =
        frame.state.world_from_body.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    EXPECT_LT((up - up_in_body).norm(), 1e-9);
  }
  std::cout << "EuRoC static micro: " << summary.message << "; gyro bias error " << gyro_error
            << " rad/s, up error " << up_error_deg << " deg, drift " << drift_m << " m\n";
  EXPECT_LT(gyro_error, 2e-3);
  EXPECT_LT(up_error_deg, 1.0);
  EXPECT_LT(drift_m, 0.05);

  const std::filesystem::path out = testing::MakeScratchFolder("vio_euroc_static");
  WriteVioResult(out, result);
  EXPECT_EQ(CountLines(out / "states.csv"), static_cast<int>(sequence.images.size()) + 1);
  const std::string summary_text = ReadTextFile(out / "vio_summary.txt");
  EXPECT_NE(summary_text.find("visual_initialized: false"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

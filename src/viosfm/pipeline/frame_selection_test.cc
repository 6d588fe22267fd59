#include "viosfm/pipeline/frame_selection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "viosfm/io/euroc.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;

TEST(SelectFrames, EurocStaticStartIsAllStatic) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence sequence = ReadEurocDataset(root);
  ASSERT_EQ(sequence.num_images(), 95u);
  for (const StaticSource source : {StaticSource::kAuto, StaticSource::kImu,
                                    StaticSource::kTrajectory, StaticSource::kImuAndTrajectory}) {
    FrameSelectionOptions options;
    options.static_source = source;
    const FrameSelection selection = SelectFrames(sequence, options);
    EXPECT_EQ(selection.status, FrameSelectionStatus::kNoMovingFrames)
        << StaticSourceName(source) << ": " << selection.message;
    EXPECT_THAT(selection.message, HasSubstr("static: no moving frames"));
    EXPECT_TRUE(selection.kept.empty());
    EXPECT_EQ(selection.Count(FrameDecision::kStatic), 95u);
  }
  // Without trimming it is only downsampled: 20 Hz -> 10 Hz.
  FrameSelectionOptions options;
  options.trim_static = false;
  const FrameSelection selection = SelectFrames(sequence, options);
  ASSERT_TRUE(selection.ok());
  EXPECT_EQ(selection.kept.size(), 48u);
}

SimulatedSequence Simulate(double static_start_s, double duration_s) {
  SimulationOptions options;
  options.duration_s = duration_s;
  options.static_start_s = static_start_s;
  options.camera_rate_hz = 20.0;
  options.seed = 4;
  options.render_images = false;  // motion and IMU only: no textures to build
  return SimulateSequence(options);
}

TEST(SelectFrames, SimulatedStaticStartIsTrimmedAndRateHalved) {
  const SimulatedSequence simulated = Simulate(2.0, 6.0);
  const Sequence& sequence = simulated.sequence;
  const timestamp_ns_t start = sequence.images.front().timestamp_ns;
  const FrameSelection selection = SelectFrames(sequence, FrameSelectionOptions());
  ASSERT_TRUE(selection.ok()) << selection.message;
  std::cout << selection.message << "; motion starts at "
            << NsToSeconds(selection.motion_start_ns - start) << " s (truth 2 s)\n";
  const double first_kept_s =
      NsToSeconds(sequence.images[selection.kept.front()].timestamp_ns - start);
  EXPECT_NEAR(first_kept_s, 2.0, 0.25);
  EXPECT_NEAR(NsToSeconds(selection.motion_start_ns - start), 2.0, 0.25);
  // The walk never stops: nothing is trimmed at the end.
  EXPECT_EQ(selection.Count(FrameDecision::kStaticEnd), 0u);
  EXPECT_GE(selection.kept.back(), sequence.num_images() - 2);
  // 20 Hz -> 10 Hz: every other frame.
  for (size_t i = 1; i < selection.kept.size(); ++i) {
    EXPECT_EQ(selection.kept[i] - selection.kept[i - 1], 2u);
  }
  EXPECT_EQ(selection.Count(FrameDecision::kKept) + selection.Count(FrameDecision::kDownsampled) +
                selection.Count(FrameDecision::kStaticStart),
            sequence.num_images());
  for (size_t k = 0; k < selection.kept.front(); ++k) {
    EXPECT_EQ(selection.decisions[k], FrameDecision::kStaticStart);
  }

  // The trajectory source (ground truth) finds the same start, more coarsely.
  FrameSelectionOptions by_trajectory;
  by_trajectory.static_source = StaticSource::kTrajectory;
  const FrameSelection from_poses = SelectFrames(sequence, by_trajectory);
  ASSERT_TRUE(from_poses.ok());
  const double trajectory_start_s =
      NsToSeconds(sequence.images[from_poses.kept.front()].timestamp_ns - start);
  std::cout << "trajectory source: first kept frame at " << trajectory_start_s << " s\n";
  EXPECT_NEAR(trajectory_start_s, 2.0, 0.5);

  // No static start: nothing trimmed.
  const SimulatedSequence moving_from_start = Simulate(0.0, 3.0);
  const Sequence& moving = moving_from_start.sequence;
  FrameSelectionOptions keep_rate;
  keep_rate.target_rate_hz = 0.0;
  const FrameSelection all = SelectFrames(moving, keep_rate);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all.kept.size(), moving.num_images());
}

// A hand-made IMU: still, a rotation with a pause in the middle, still again.
Sequence SyntheticImuSequence(double rate_hz, double duration_s, double move_begin_s,
                              double move_end_s, double pause_begin_s, double pause_end_s) {
  Sequence sequence;
  Random random(5);
  const auto moving = [&](double t) {
    return t >= move_begin_s && t <= move_end_s && !(t >= pause_begin_s && t <= pause_end_s);
  };
  for (int i = 0; static_cast<double>(i) / 200.0 <= duration_s; ++i) {
    const double t = i / 200.0;
    ImuSample sample;
    sample.timestamp_ns = SecondsToNs(t);
    sample.gyro = Eigen::Vector3d(0.01, -0.02, 0.05);  // bias
    sample.accel = Eigen::Vector3d(0.0, 0.0, 9.81);
    if (moving(t)) {
      sample.gyro += Eigen::Vector3d(0.0, 0.0, 0.8 * std::sin(3.0 * t));
      sample.accel += Eigen::Vector3d(1.5 * std::sin(2.0 * t), 1.0 * std::cos(2.5 * t), 0.0);
    }
    for (int k = 0; k < 3; ++k) {
      sample.gyro[k] += random.Normal(0.0, 0.003);
      sample.accel[k] += random.Normal(0.0, 0.05);
    }
    sequence.imu.push_back(sample);
  }
  for (int k = 0; k / rate_hz <= duration_s; ++k) {
    sequence.images.push_back({SecondsToNs(k / rate_hz), "x.png"});
  }
  return sequence;
}

TEST(SelectFrames, TrimsBothEndsButNotAPauseInTheMiddle) {
  const Sequence sequence = SyntheticImuSequence(30.0, 12.0, 3.0, 8.5, 5.0, 6.5);
  FrameSelectionOptions options;
  const FrameSelection selection = SelectFrames(sequence, options);
  ASSERT_TRUE(selection.ok()) << selection.message;
  std::cout << selection.message << "; motion " << NsToSeconds(selection.motion_start_ns) << " - "
            << NsToSeconds(selection.motion_end_ns) << " s (truth 3 - 8.5 s)\n";
  EXPECT_NEAR(NsToSeconds(selection.motion_start_ns), 3.0, 0.25);
  EXPECT_NEAR(NsToSeconds(selection.motion_end_ns), 8.5, 0.25);
  EXPECT_NEAR(NsToSeconds(sequence.images[selection.kept.front()].timestamp_ns), 3.0, 0.25);
  EXPECT_NEAR(NsToSeconds(sequence.images[selection.kept.back()].timestamp_ns), 8.5, 0.25);
  // 30 Hz -> 10 Hz: every third frame, through the pause.
  for (size_t i = 1; i < selection.kept.size(); ++i) {
    EXPECT_EQ(selection.kept[i] - selection.kept[i - 1], 3u);
  }
  EXPECT_GT(selection.Count(FrameDecision::kStaticStart), 80u);
  EXPECT_GT(selection.Count(FrameDecision::kStaticEnd), 95u);
}

// The recording of the test above as it is made, a frame and 1/30 s of
// IMU at a time: the frames selected as it grows are those SelectFrames
// keeps from the whole recording (the pause in the middle kept, the static
// end not), each taken within the lag and a frame after its stamp; the
// static end leaves nothing for the end to take.
TEST(GrowingFrameSelection, TakesWhatTheWholeRecordingKeeps) {
  const Sequence whole = SyntheticImuSequence(30.0, 12.0, 3.0, 8.5, 5.0, 6.5);
  const FrameSelectionOptions options;
  const FrameSelection expected = SelectFrames(whole, options);
  GrowingFrameSelection growing(options);
  Sequence so_far;
  size_t next_sample = 0;
  std::vector<size_t> taken;
  double latest_delay_s = 0.0;
  for (const SequenceImage& image : whole.images) {
    while (next_sample < whole.imu.size() &&
           whole.imu[next_sample].timestamp_ns <= image.timestamp_ns) {
      so_far.imu.push_back(whole.imu[next_sample++]);
    }
    so_far.images.push_back(image);
    size_t decided = 0;
    for (const size_t k : growing.Update(so_far, &decided)) {
      taken.push_back(k);
      latest_delay_s =
          std::max(latest_delay_s, NsToSeconds(image.timestamp_ns - whole.images[k].timestamp_ns));
    }
    EXPECT_LE(decided, so_far.images.size());
  }
  const size_t before_end = taken.size();
  FrameSelection selection;
  for (const size_t k : growing.Finish(whole, &selection)) taken.push_back(k);
  EXPECT_EQ(taken, expected.kept);
  EXPECT_EQ(selection.kept, expected.kept);
  EXPECT_EQ(before_end, taken.size());
  EXPECT_LE(latest_delay_s, NsToSeconds(growing.Lag()) + 1.0 / 30.0 + 1e-6);
  std::cout << "as it grew: " << taken.size() << " frames, " << before_end
            << " before the end, the latest " << latest_delay_s << " s after its stamp (lag "
            << NsToSeconds(growing.Lag()) << " s)\n";
}

TEST(SelectFrames, StatusesAndErrors) {
  Sequence empty;
  EXPECT_EQ(SelectFrames(empty, {}).status, FrameSelectionStatus::kNoImages);

  // No IMU, no trajectory: auto keeps the static frames and only downsamples.
  Sequence images_only;
  for (int k = 0; k < 40; ++k) images_only.images.push_back({SecondsToNs(k / 20.0), "x.png"});
  const FrameSelection selection = SelectFrames(images_only, {});
  ASSERT_TRUE(selection.ok());
  EXPECT_EQ(selection.kept.size(), 20u);
  FrameSelectionOptions imu_only;
  imu_only.static_source = StaticSource::kImu;
  EXPECT_THROW(SelectFrames(images_only, imu_only), InputError);
  FrameSelectionOptions trajectory_only;
  trajectory_only.static_source = StaticSource::kTrajectory;
  EXPECT_THROW(SelectFrames(images_only, trajectory_only), InputError);
  // A given trajectory that never moves: all static.
  Trajectory still;
  for (int k = 0; k < 40; ++k) still.poses.push_back({SecondsToNs(k / 20.0), Rigid3d()});
  EXPECT_EQ(SelectFrames(images_only, trajectory_only, &still).status,
            FrameSelectionStatus::kNoMovingFrames);

  FrameSelectionOptions bad;
  bad.static_window_s = 0.0;
  EXPECT_THAT(bad.Validate(), HasSubstr("static_window_s"));
  EXPECT_THROW(SelectFrames(images_only, bad), InputError);
  EXPECT_EQ(ParseStaticSource("IMU"), StaticSource::kImu);
  EXPECT_THROW(ParseStaticSource("vision"), InputError);
}

}  // namespace
}  // namespace viosfm

// The whole pipeline where the VIO is sparse, broken or absent: a keyframe
// trajectory file with seconds between its poses, one with a
// re-initialisation, the images alone, and sparse images with their IMU.
// Small simulated keyframe sequences (half resolution) with exact ground
// truth; a few seconds each.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/pipeline/pipeline.h"
#include "viosfm/pipeline/pipeline_test_fixture.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using pipeline_testing::HalfResolutionRoom;
using pipeline_testing::SmallRunOptions;

struct KeyframeSequence {
  fs::path dataset;
  fs::path vio_file;                        // the VIO's poses at the keyframes only
  std::map<timestamp_ns_t, Rigid3d> truth;  // world_from_body at every keyframe
  size_t num_images = 0;
  double path_m = 0.0;  // the keyframes' path length
};

// A walk in the simulated room seen in keyframes `min_gap_s` to
// `max_gap_s` apart, with a realistic VIO (re-initialised at `reinit_s`
// after the start when given) whose trajectory file holds the keyframes'
// poses only, as a keyframe-based VIO writes it.
KeyframeSequence MakeKeyframeSequence(const std::string& name, double duration_s, double min_gap_s,
                                      double max_gap_s,
                                      std::optional<double> reinit_s = std::nullopt) {
  SimulationOptions sim = HalfResolutionRoom(11);
  sim.duration_s = duration_s;
  sim.static_start_s = 0.5;
  sim.camera_rate_hz = 20.0;
  sim.keyframes.enabled = true;
  sim.keyframes.min_gap_s = min_gap_s;
  sim.keyframes.max_gap_s = max_gap_s;
  sim.vio_profile = "realistic";
  if (reinit_s) {
    sim.realistic_vio.reinit_times_s = {*reinit_s};
    sim.realistic_vio.reinit_gap_s = 1.5;
  }
  const SimulatedSequence simulated = SimulateSequence(sim);
  KeyframeSequence result;
  const fs::path folder = testing::MakeScratchFolder("sfm_core_" + name);
  result.dataset = folder / "dataset";
  WriteSimulatedSequence(result.dataset, simulated, sim);
  result.num_images = simulated.sequence.images.size();
  Trajectory at_keyframes;
  size_t k = 0;
  for (size_t i = 0; i < simulated.sequence.images.size(); ++i) {
    const timestamp_ns_t stamp = simulated.sequence.images[i].timestamp_ns;
    result.truth[stamp] = simulated.motion.WorldFromBody(simulated.FrameTime(i));
    while (k < simulated.vio_body.size() && simulated.vio_body.poses[k].timestamp_ns < stamp) ++k;
    if (k < simulated.vio_body.size() && simulated.vio_body.poses[k].timestamp_ns == stamp) {
      at_keyframes.poses.push_back(simulated.vio_body.poses[k]);
    }
  }
  const Rigid3d* previous = nullptr;
  for (const auto& [stamp, pose] : result.truth) {
    if (previous != nullptr) result.path_m += (pose.translation - previous->translation).norm();
    previous = &pose;
  }
  result.vio_file = folder / "vio_keyframes.tum";
  WriteTumTrajectory(result.vio_file, at_keyframes);
  return result;
}

PipelineOptions KeyframeRunOptions(const KeyframeSequence& sequence, const fs::path& out) {
  PipelineOptions options = SmallRunOptions(sequence.dataset, sequence.vio_file, out, 800);
  options.frame_selection.target_rate_hz = 0.0;  // every keyframe
  options.num_threads = 2;
  return options;
}

// Without a VIO the images must carry the model alone: each frame matched
// with its ten nearest in time (the small settings' four leave the
// frames a second apart too few 2D-3D matches).
PipelineOptions ImagesRunOptions(const KeyframeSequence& sequence, const fs::path& out) {
  PipelineOptions options = KeyframeRunOptions(sequence, out);
  options.vio_trajectory.clear();
  options.verification.pairs.num_temporal_neighbors = 10;
  return options;
}

// Sim(3) RMSE (m) of the run's body trajectory against the truth, and the
// scale of the trajectory (1 / the alignment's).
double SimilarityAte(const fs::path& out, const KeyframeSequence& sequence, double* scale) {
  std::vector<Eigen::Vector3d> estimate, truth;
  for (const StampedPose& pose : ReadTumTrajectory(out / "trajectory_body.tum").poses) {
    const auto it = sequence.truth.find(pose.timestamp_ns);
    if (it == sequence.truth.end()) continue;
    estimate.push_back(pose.world_from_frame.translation);
    truth.push_back(it->second.translation);
  }
  const std::optional<Sim3d> aligned = AlignPointsUmeyama(estimate, truth, true);
  if (!aligned) return 1e9;
  *scale = 1.0 / aligned->scale;
  double sum = 0.0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    sum += (*aligned * estimate[i] - truth[i]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(estimate.size()));
}

TEST(SfmCorePipelineTest, AKeyframeTrajectoryWithGapsIsOneSegment) {
  const KeyframeSequence sequence = MakeKeyframeSequence("keyframes", 16.0, 0.3, 2.0);
  const fs::path out = sequence.dataset.parent_path() / "out";
  const PipelineSummary summary = RunPipeline(KeyframeRunOptions(sequence, out));
  std::cerr << summary.ToString() << "\n";
  // Gaps of up to 2 s between the VIO's poses: most confirmed by the pairs
  // across them, the others crossed by the VIO as it moves elsewhere; the
  // whole file one segment, every keyframe posed.
  EXPECT_GT(summary.vio_gaps.num_gaps, 0);
  EXPECT_GT(2 * summary.vio_gaps.num_confirmed, summary.vio_gaps.num_gaps);
  EXPECT_EQ(summary.vio_gaps.num_confirmed + summary.vio_gaps.num_unseen_kept,
            summary.vio_gaps.num_gaps);
  EXPECT_EQ(summary.num_vio_segments, 1);
  EXPECT_EQ(summary.num_frames_registered + summary.num_frames_vio_only, sequence.num_images);
  double scale = 0.0;
  EXPECT_LT(SimilarityAte(out, sequence, &scale), 0.01);
}

TEST(SfmCorePipelineTest, AReinitialisationInAKeyframeTrajectoryIsABreak) {
  const KeyframeSequence sequence = MakeKeyframeSequence("reinit", 16.0, 0.3, 1.2, 8.0);
  const fs::path out = sequence.dataset.parent_path() / "out";
  const PipelineSummary summary = RunPipeline(KeyframeRunOptions(sequence, out));
  std::cerr << summary.ToString() << "\n";
  // The 1.5 s gap of the re-initialisation, where the VIO restarted in a
  // new world frame, is a break; the images join the two sides again.
  EXPECT_GE(summary.vio_gaps.num_jumps + summary.vio_gaps.num_unseen, 1);
  EXPECT_GE(summary.num_vio_segments, 2);
  EXPECT_EQ(summary.num_frames_registered + summary.num_frames_vio_only, sequence.num_images);
  double scale = 0.0;
  EXPECT_LT(SimilarityAte(out, sequence, &scale), 0.01);
}

TEST(SfmCorePipelineTest, TheImagesAloneMakeTheModel) {
  // Frames 0.1 to 0.3 s apart: the images see each other all the way.
  const KeyframeSequence sequence = MakeKeyframeSequence("images_only", 8.0, 0.1, 0.3);
  const fs::path out = sequence.dataset.parent_path() / "out";
  PipelineOptions options = ImagesRunOptions(sequence, out);
  options.use_imu = false;
  const PipelineSummary summary = RunPipeline(options);
  std::cerr << summary.ToString() << "\n";
  EXPECT_TRUE(summary.mapper.images_only);
  EXPECT_EQ(summary.num_frames_registered, sequence.num_images);
  ASSERT_EQ(summary.mapper.frames_per_model.size(), 1u);
  // The images alone, 800 keypoints of 376x240 a frame: the shape within
  // 1 % of the path (see docs/benchmarks.md, "Without a VIO, or with a sparse one").
  double scale = 0.0;
  EXPECT_LT(SimilarityAte(out, sequence, &scale), 0.01 * sequence.path_m);
}

TEST(SfmCorePipelineTest, SparseImagesWithTheirImuAreMetric) {
  const KeyframeSequence sequence = MakeKeyframeSequence("sparse_imu", 24.0, 0.5, 1.5);
  const fs::path out = sequence.dataset.parent_path() / "out";
  const PipelineSummary summary = RunPipeline(ImagesRunOptions(sequence, out));
  std::cerr << summary.ToString() << "\n";
  // Frames 0.5 to 1.5 s apart: no VIO, the IMU scales and levels the
  // model. Where the walk turns faster than the frames see each other, the
  // frames after the turn form a model of their own: every frame is posed
  // in one model or another.
  EXPECT_TRUE(summary.mapper.images_only);
  EXPECT_EQ(summary.num_frames_registered + summary.mapper.num_frames_in_other_models,
            sequence.num_images);
  EXPECT_GE(2 * summary.num_frames_registered, sequence.num_images);
  EXPECT_GT(summary.mapper.num_inertial_factors, 0);
  double scale = 0.0;
  EXPECT_LT(SimilarityAte(out, sequence, &scale), 0.01);
  EXPECT_NEAR(scale, 1.0, 0.02);
}

}  // namespace
}  // namespace viosfm

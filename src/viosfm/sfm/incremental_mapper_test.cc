#include "viosfm/sfm/incremental_mapper.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "viosfm/geometry/alignment.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/synthetic_test_scene.h"

namespace viosfm {
namespace {

using testing::MakeSyntheticSequence;
using testing::SyntheticSequence;
using testing::SyntheticSequenceOptions;

constexpr double kRadToDeg = 180.0 / M_PI;

SyntheticSequenceOptions SequenceOptions(int num_frames) {
  SyntheticSequenceOptions options;
  options.num_frames = num_frames;
  options.step_m = 0.08;
  options.max_frame_gap = 8;
  options.track_segment_frames = 30;
  return options;
}

// A core holding every frame of `sequence` (unregistered) and the tracks of
// its verified pairs.
IncrementalMapper MakeCore(const SyntheticSequence& sequence) {
  IncrementalMapperOptions options;
  options.init_min_num_inliers = 50;
  IncrementalMapper core(options, TriangulationOptions(), PointFilterOptions(),
                         FrameRegistrationOptions(), 1);
  core.reconstruction().AddCamera(sequence.camera);
  for (const MapperImage& input : sequence.input.images) {
    Image image;
    image.image_id = input.image_id;
    image.camera_id = input.camera_id;
    image.name = input.name;
    image.timestamp_ns = input.timestamp_ns;
    for (const FeatureKeypoint& keypoint : input.keypoints) {
      Point2D point2D;
      point2D.xy = Eigen::Vector2d(keypoint.x, keypoint.y);
      image.points2D.push_back(point2D);
    }
    core.AddFrame(std::move(image));
  }
  core.SetTracks(BuildTracks(sequence.input.verified_pairs).tracks);
  return core;
}

// Sim(3) RMSE (m) of the camera centres of the registered frames of model m
// against the truth, and how many there were.
double ModelAte(const IncrementalMapper& core, int m, const SyntheticSequence& sequence,
                size_t* num_frames) {
  std::vector<Eigen::Vector3d> estimate, truth;
  for (const image_t image_id : core.model(m).registered) {
    estimate.push_back(core.reconstruction().GetImage(image_id).ProjectionCenter());
    truth.push_back(ProjectionCenter(sequence.cams_from_world[core.FrameIndex(image_id)]));
  }
  *num_frames = estimate.size();
  const std::optional<Sim3d> truth_from_estimate = AlignPointsUmeyama(estimate, truth, true);
  if (!truth_from_estimate) return 1e9;
  double sum = 0.0;
  for (size_t k = 0; k < estimate.size(); ++k) {
    sum += (*truth_from_estimate * estimate[k] - truth[k]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(estimate.size()));
}

TEST(IncrementalMapperTest, InitialPairHasTheTrueRelativePose) {
  const SyntheticSequence sequence = MakeSyntheticSequence(SequenceOptions(40));
  IncrementalMapper core = MakeCore(sequence);
  std::vector<size_t> candidates;
  for (size_t i = 0; i < core.NumFrames(); ++i) candidates.push_back(i);
  const std::optional<InitialPair> pair =
      core.FindInitialPair(candidates, sequence.input.verified_pairs);
  ASSERT_TRUE(pair.has_value());
  // The pairs hold frames at most 8 apart: the widest baseline wins once
  // no pair reaches the larger angles.
  EXPECT_GE(pair->median_angle_deg, 2.0);
  const Rigid3d true_cam2_from_cam1 =
      sequence.cams_from_world[pair->frame2] * sequence.cams_from_world[pair->frame1].Inverse();
  EXPECT_LT(pair->cam2_from_cam1.rotation.angularDistance(true_cam2_from_cam1.rotation) * kRadToDeg,
            0.1);
  const double direction_error_deg =
      std::acos(std::clamp(pair->cam2_from_cam1.translation.normalized().dot(
                               true_cam2_from_cam1.translation.normalized()),
                           -1.0, 1.0)) *
      kRadToDeg;
  EXPECT_LT(direction_error_deg, 1.0);

  const int m = core.InitializeModel(*pair);
  ASSERT_EQ(m, 0);
  EXPECT_EQ(core.model(0).registered.size(), 2u);
  EXPECT_GT(core.reconstruction().NumPoints3D(), 50u);
  // Its points at the true depths, up to the pair's unknown scale.
  const double true_baseline = (ProjectionCenter(sequence.cams_from_world[pair->frame2]) -
                                ProjectionCenter(sequence.cams_from_world[pair->frame1]))
                                   .norm();
  const Rigid3d& cam1_from_world = sequence.cams_from_world[pair->frame1];
  std::vector<double> errors;
  for (const auto& [point_id, point] : core.reconstruction().Points3D()) {
    const TrackElement& element = point.track.front();
    const size_t frame = core.FrameIndex(element.image_id);
    const int truth_index = sequence.point_of_keypoint[frame][element.point2D_idx];
    const double true_depth = (cam1_from_world * sequence.points[truth_index]).z();
    const double depth = point.xyz.z() * true_baseline;
    errors.push_back(std::abs(depth - true_depth) / true_depth);
  }
  std::sort(errors.begin(), errors.end());
  // Two views 4 to 5 degrees apart, keypoints with 0.5 px of noise.
  EXPECT_LT(errors[errors.size() / 2], 0.02);
  EXPECT_LT(errors.back(), 0.2);
}

TEST(IncrementalMapperTest, RegistersAChainOfFramesFromTheImagesAlone) {
  const SyntheticSequence sequence = MakeSyntheticSequence(SequenceOptions(60));
  IncrementalMapper core = MakeCore(sequence);
  std::vector<size_t> candidates;
  for (size_t i = 0; i < core.NumFrames(); ++i) candidates.push_back(i);
  const std::optional<InitialPair> pair =
      core.FindInitialPair(candidates, sequence.input.verified_pairs);
  ASSERT_TRUE(pair.has_value());
  ASSERT_EQ(core.InitializeModel(*pair), 0);
  const std::vector<size_t> registered = core.RegisterNextFrames(candidates);
  EXPECT_EQ(registered.size() + 2, core.NumFrames());
  BundleAdjustmentOptions ba;
  ba.num_threads = 1;
  core.AdjustModel(0, ba);
  size_t num_frames = 0;
  const double ate = ModelAte(core, 0, sequence, &num_frames);
  EXPECT_EQ(num_frames, core.NumFrames());
  // 4.7 m of path, keypoints with 0.5 px of noise.
  EXPECT_LT(ate, 0.01);
}

TEST(IncrementalMapperTest, MergesTwoModelsByTheirCommonPoints) {
  const SyntheticSequence sequence = MakeSyntheticSequence(SequenceOptions(60));
  IncrementalMapper core = MakeCore(sequence);
  // Model 0 at the true poses of frames [0, 36), model 1 at the poses of
  // frames [36, 60) moved by a known similarity; the tracks cross.
  const Sim3d moved(
      1.7, Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(4.0, -2.0, 1.0));
  const int first = core.NewModel(false);
  const int second = core.NewModel(false);
  std::vector<size_t> frames0, frames1;
  for (size_t i = 0; i < core.NumFrames(); ++i) {
    if (i < 36) {
      core.Register(i, first, sequence.cams_from_world[i]);
      frames0.push_back(i);
    } else {
      frames1.push_back(i);
    }
  }
  core.SetGauge(first, core.ImageId(0));
  for (const size_t i : frames1) core.Register(i, second, sequence.cams_from_world[i]);
  core.SetGauge(second, core.ImageId(frames1.front()));
  std::vector<image_t> second_ids;
  for (const size_t i : frames1) second_ids.push_back(core.ImageId(i));
  core.TriangulateFrames(frames0);
  core.TriangulateFrames(frames1);
  TransformFrames(moved, second_ids, &core.reconstruction());
  ASSERT_EQ(core.NumModels(), 2);

  const std::optional<ModelMerge> merge = core.TryMergeModels();
  ASSERT_TRUE(merge.has_value());
  EXPECT_EQ(core.NumModels(), 1);
  EXPECT_EQ(core.model(0).registered.size(), core.NumFrames());
  // The similarity found takes model 1 back to model 0's frame: the inverse
  // of the one applied, as well as points triangulated from 0.5 px noisy
  // keypoints tell it.
  const Sim3d expected = moved.Inverse();
  EXPECT_NEAR(merge->into_from_from.scale, expected.scale, 0.01 * expected.scale);
  EXPECT_LT(merge->into_from_from.rotation.angularDistance(expected.rotation) * kRadToDeg, 0.5);
  EXPECT_LT((merge->into_from_from.translation - expected.translation).norm(), 0.05);
  // Adjusted as one model, every frame back at its true pose.
  BundleAdjustmentOptions ba;
  ba.num_threads = 1;
  core.AdjustModel(0, ba);
  size_t num_frames = 0;
  EXPECT_LT(ModelAte(core, 0, sequence, &num_frames), 0.005);
  EXPECT_EQ(num_frames, core.NumFrames());
}

TEST(IncrementalMapperTest, ModelsWithoutCommonPointsStaySeparate) {
  const SyntheticSequence sequence = MakeSyntheticSequence(SequenceOptions(60));
  IncrementalMapper core = MakeCore(sequence);
  const int first = core.NewModel(false);
  const int second = core.NewModel(false);
  std::vector<size_t> frames0, frames1;
  for (size_t i = 0; i < 10; ++i) {
    core.Register(i, first, sequence.cams_from_world[i]);
    frames0.push_back(i);
  }
  for (size_t i = 50; i < 60; ++i) {
    core.Register(i, second, sequence.cams_from_world[i]);
    frames1.push_back(i);
  }
  core.TriangulateFrames(frames0);
  core.TriangulateFrames(frames1);
  EXPECT_FALSE(core.TryMergeModels().has_value());
  EXPECT_EQ(core.NumModels(), 2);
}

TEST(IncrementalMapperTest, BatchedMapperWithoutAnyVioPoseUsesTheImages) {
  SyntheticSequenceOptions options = SequenceOptions(90);
  const SyntheticSequence sequence = MakeSyntheticSequence(options);
  BatchedMapperInput input = sequence.input;
  for (MapperImage& image : input.images) image.vio_cam_from_world.reset();
  BatchedMapperOptions mapper;
  mapper.show_progress = false;
  mapper.num_threads = 1;
  mapper.batch_size = 30;
  mapper.incremental.init_min_num_inliers = 50;
  BatchedMapperSummary summary;
  const Reconstruction model = RunBatchedMapper(input, mapper, &summary);
  EXPECT_TRUE(summary.images_only);
  EXPECT_EQ(summary.num_registered, 90);
  EXPECT_EQ(summary.num_unposed, 0);
  ASSERT_EQ(summary.frames_per_model.size(), 1u);
  std::vector<Eigen::Vector3d> estimate, truth;
  for (size_t i = 0; i < input.images.size(); ++i) {
    estimate.push_back(model.GetImage(input.images[i].image_id).ProjectionCenter());
    truth.push_back(ProjectionCenter(sequence.cams_from_world[i]));
  }
  const std::optional<Sim3d> aligned = AlignPointsUmeyama(estimate, truth, true);
  ASSERT_TRUE(aligned.has_value());
  double sum = 0.0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    sum += (*aligned * estimate[i] - truth[i]).squaredNorm();
  }
  EXPECT_LT(std::sqrt(sum / static_cast<double>(estimate.size())), 0.01);
}

}  // namespace
}  // namespace viosfm

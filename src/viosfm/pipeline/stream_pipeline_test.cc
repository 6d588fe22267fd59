// The streamed run (stream_pipeline.h) against the run of pipeline.h on the
// shared fixture's simulated walk.
#include "viosfm/pipeline/stream_pipeline.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <utility>

#include "viosfm/io/euroc_replay.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/pipeline/pipeline_test_fixture.h"

namespace viosfm {
namespace {

using namespace pipeline_testing;  // NOLINT
using ::testing::HasSubstr;

using PairKey = std::pair<std::string, std::string>;

std::map<PairKey, PairDecision> DecisionsOf(const fs::path& out) {
  std::map<PairKey, PairDecision> decisions;
  for (PairDecision& decision : ReadPairDecisionsCsv(out / "verification" / "pairs.csv")) {
    decisions.emplace(PairKey{decision.name1, decision.name2}, std::move(decision));
  }
  return decisions;
}

std::set<PairKey> PairsFrom(const std::map<PairKey, PairDecision>& decisions,
                            const std::string& source) {
  std::set<PairKey> pairs;
  for (const auto& [key, decision] : decisions) {
    if (decision.source == source) pairs.insert(key);
  }
  return pairs;
}

// With the VIO file of the fixture: the same frames, the same temporal
// pairs with the same decisions (retrieval among earlier frames gives other
// retrieval pairs), every frame registered, and a model as accurate as the
// run of pipeline.h against the simulator's truth.
TEST(StreamPipelineTest, StreamedRunGivesTheModelOfTheStagesInTurn) {
  const Fixture& f = SharedFixture();
  PipelineOptions options = SmallOptions(f, f.folder / "out_stream");
  options.stream = true;
  options.stream_vocabulary_frames = 12;
  const PipelineSummary s = RunPipeline(options);
  std::cerr << s.ToString() << "\n";
  EXPECT_TRUE(s.stream.streamed);
  EXPECT_EQ(s.num_frames_selected, f.summary.num_frames_selected);
  EXPECT_EQ(s.frame_selection.kept, f.summary.frame_selection.kept);
  EXPECT_EQ(s.num_frames_registered, s.num_frames_selected);
  EXPECT_EQ(s.num_frames_unposed, 0u);
  EXPECT_EQ(s.stream.num_vocabulary_frames, 12u);
  ASSERT_EQ(s.stages.size(), 5u);
  EXPECT_EQ(s.stages[1].name, "stream");
  EXPECT_GE(s.stream.mapper_seconds, s.stream.verification_seconds);
  EXPECT_GE(s.stream.seconds_after_last_frame, 0.0);

  const std::map<PairKey, PairDecision> streamed = DecisionsOf(f.folder / "out_stream");
  const std::map<PairKey, PairDecision> in_turn = DecisionsOf(f.out);
  const std::set<PairKey> temporal = PairsFrom(streamed, "temporal");
  EXPECT_EQ(temporal, PairsFrom(in_turn, "temporal"));
  EXPECT_FALSE(PairsFrom(streamed, "retrieval").empty());
  size_t num_common = 0;
  for (const auto& [key, decision] : streamed) {
    const auto other = in_turn.find(key);
    if (other == in_turn.end()) continue;
    ++num_common;
    EXPECT_EQ(decision.accepted, other->second.accepted) << key.first << " " << key.second;
    EXPECT_EQ(decision.num_inliers, other->second.num_inliers) << key.first << " " << key.second;
  }
  EXPECT_GE(num_common, temporal.size());
  EXPECT_EQ(s.verification.num_pairs, streamed.size());

  ASSERT_TRUE(s.evaluation.has_value());
  ASSERT_TRUE(f.summary.evaluation.has_value());
  EXPECT_LT(s.evaluation->ate_rmse_m, 0.9 * s.evaluation->vio_ate_rmse_m);
  EXPECT_LT(s.evaluation->ate_rmse_m, 1.25 * f.summary.evaluation->ate_rmse_m);
  std::cerr << "streamed: ATE " << s.evaluation->ate_rmse_m << " m, stages in turn "
            << f.summary.evaluation->ate_rmse_m << " m\n";

  // summary.json has the stream's figures; the folder is complete.
  const nlohmann::json json =
      nlohmann::json::parse(ReadTextFile(f.folder / "out_stream" / "summary.json"));
  EXPECT_DOUBLE_EQ(json["stream"]["seconds_after_last_frame"].get<double>(),
                   s.stream.seconds_after_last_frame);
  EXPECT_EQ(json["stream"]["vocabulary_frames"], 12);
}

// viosfm's own VIO streamed: its poses are those of the run in turn, bit for
// bit (the fingerprint's vio.poses, written when the VIO ends), each frame
// taken once its pose is settled, and the model as close to the truth.
TEST(StreamPipelineTest, OwnVioStreamedGivesItsPosesAsTheyAre) {
  const Fixture& f = SharedFixture();
  PipelineOptions in_turn_options = SmallOptions(f, f.folder / "own_vio_in_turn");
  in_turn_options.vio_trajectory.clear();
  const PipelineSummary in_turn = RunPipeline(in_turn_options);
  PipelineOptions options = SmallOptions(f, f.folder / "own_vio_stream");
  options.vio_trajectory.clear();
  options.stream = true;
  const PipelineSummary s = RunPipeline(options);
  const RunFingerprint in_turn_fingerprint =
      ReadRunFingerprint(f.folder / "own_vio_in_turn" / "fingerprint.json");
  const RunFingerprint streamed_fingerprint =
      ReadRunFingerprint(f.folder / "own_vio_stream" / "fingerprint.json");
  ASSERT_NE(streamed_fingerprint.Find("vio.poses"), nullptr);
  EXPECT_EQ(*streamed_fingerprint.Find("vio.poses"), *in_turn_fingerprint.Find("vio.poses"));
  EXPECT_EQ(s.fingerprint, in_turn.fingerprint);
  EXPECT_EQ(s.num_frames_selected, in_turn.num_frames_selected);
  EXPECT_EQ(s.num_frames_without_vio_pose, in_turn.num_frames_without_vio_pose);
  EXPECT_EQ(s.num_frames_registered + s.num_frames_vio_only + s.num_frames_unposed,
            s.num_frames_selected);
  EXPECT_GE(s.num_frames_registered, in_turn.num_frames_registered - 2);
  ASSERT_TRUE(s.evaluation.has_value());
  EXPECT_LT(s.evaluation->ate_rmse_m, 0.03);
  // The VIO decodes every image once; the features take the selected ones
  // from the frame cache (beside the VIO, or after it).
  EXPECT_EQ(s.images.decodes, s.num_frames_in);
  EXPECT_EQ(s.features.num_extracted, s.num_frames_selected);
  EXPECT_GT(s.stream.vio_seconds, 0.0);
  std::cerr << "own VIO streamed: " << s.num_frames_registered << " frames, ATE "
            << s.evaluation->ate_rmse_m << " m; in turn " << in_turn.num_frames_registered << ", "
            << in_turn.evaluation->ate_rmse_m << " m\n";
}

// A recording followed as it is made (viosfm replay's writer on another
// thread, at twice its pace, into a folder the run follows): the frames,
// the VIO's poses, the pairs and the model are those of the streamed run on
// the recorded dataset; the fingerprint too (the replayed files are the
// recording's, byte for byte), so a run on the finished folder would reuse
// nothing it should not. The model after every batch is in OUT/live/ while
// the run goes on, and gone once the model is complete.
TEST(StreamPipelineTest, ARecordingFollowedAsItIsMadeGivesTheRecordedRunsModel) {
  const Fixture& f = SharedFixture();
  PipelineOptions recorded = SmallOptions(f, f.folder / "follow_reference");
  recorded.vio_trajectory.clear();
  recorded.stream = true;
  const PipelineSummary reference = RunPipeline(recorded);

  const fs::path live = f.folder / "follow_recording";
  std::atomic<bool> started{false};
  std::thread recorder([&] {
    EurocReplayOptions replay;
    replay.speed = 2.0;
    started = true;
    ReplayEurocRecording(f.dataset, live, replay);
  });
  // The run starts once the recorder has written the calibration.
  while (!started || !fs::exists(live / "mav0" / "imu0" / "sensor.yaml")) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  PipelineOptions options = recorded;
  options.dataset = live;
  options.output_folder = f.folder / "follow_out";
  options.stream = false;
  options.follow = true;
  options.follow_idle_s = 1.0;
  std::atomic<bool> live_seen{false};
  std::thread watcher([&] {
    while (!fs::exists(options.output_folder / "summary.json")) {
      if (fs::exists(options.output_folder / "live" / "trajectory_body.tum")) live_seen = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  const PipelineSummary s = RunPipeline(options);
  recorder.join();
  watcher.join();
  std::cerr << s.ToString() << "\n";
  EXPECT_TRUE(s.stream.followed);
  EXPECT_EQ(s.fingerprint, reference.fingerprint);
  EXPECT_EQ(s.num_frames_in, reference.num_frames_in);
  EXPECT_EQ(s.frame_selection.kept, reference.frame_selection.kept);
  EXPECT_EQ(s.num_frames_registered, reference.num_frames_registered);
  EXPECT_EQ(s.num_frames_unposed, 0u);
  EXPECT_EQ(s.verification.num_pairs, reference.verification.num_pairs);
  EXPECT_EQ(s.verification.num_accepted, reference.verification.num_accepted);
  EXPECT_EQ(s.mapper.tracks.num_tracks, reference.mapper.tracks.num_tracks);
  ASSERT_TRUE(s.evaluation.has_value());
  ASSERT_TRUE(reference.evaluation.has_value());
  EXPECT_LT(s.evaluation->ate_rmse_m, 1.1 * reference.evaluation->ate_rmse_m + 1e-4);
  // The model came after the recording's last row: the silence that ends
  // it, then the last frames and the final adjustment.
  EXPECT_GE(s.stream.seconds_after_recording_end, options.follow_idle_s);
  EXPECT_GT(s.stream.recording_end_seconds, 1.0);  // 4.5 s at twice its pace
  EXPECT_TRUE(live_seen);
  EXPECT_FALSE(fs::exists(options.output_folder / "live"));
  std::cerr << "followed: ATE " << s.evaluation->ate_rmse_m << " m (recorded "
            << reference.evaluation->ate_rmse_m << " m), the model "
            << s.stream.seconds_after_recording_end << " s after the recording's last row\n";
}

// --follow refuses what it cannot follow, before anything is written.
TEST(StreamPipelineTest, WhatCannotBeFollowedIsRefused) {
  const Fixture& f = SharedFixture();
  PipelineOptions options = SmallOptions(f, f.folder / "follow_refused");
  options.follow = true;  // with the fixture's VIO file
  EXPECT_THAT([&] { RunPipeline(options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("own VIO")));
  options.vio_trajectory.clear();
  options.follow_idle_s = 0.0;
  EXPECT_THAT([&] { RunPipeline(options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("follow_idle_s")));
  EXPECT_FALSE(fs::exists(f.folder / "follow_refused"));
}

// A streamed run does not resume: a folder with stored data is refused
// before anything in it changes, and --overwrite starts afresh.
TEST(StreamPipelineTest, AFolderWithStoredDataIsRefusedUnlessOverwritten) {
  const Fixture& f = SharedFixture();
  const fs::path out = CopyOfTheRun(f, "stream_onto_stored");
  const std::string summary_before = ReadTextFile(out / "summary.json");
  PipelineOptions options = SmallOptions(f, out);
  options.stream = true;
  EXPECT_THAT([&] { RunPipeline(options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("does not resume")));
  EXPECT_EQ(ReadTextFile(out / "summary.json"), summary_before);
  options.overwrite = true;
  const PipelineSummary s = RunPipeline(options);
  EXPECT_EQ(s.num_frames_registered, s.num_frames_selected);
}

TEST(StreamPipelineTest, OptionsThatCannotStreamAreRefused) {
  const Fixture& f = SharedFixture();
  PipelineOptions options = SmallOptions(f, f.folder / "stream_refused");
  options.stream = true;
  options.stream_vocabulary_frames = 0;
  EXPECT_THAT([&] { RunPipeline(options); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("stream_vocabulary_frames")));
  EXPECT_FALSE(fs::exists(f.folder / "stream_refused"));
}

}  // namespace
}  // namespace viosfm

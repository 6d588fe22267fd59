// The stream of a `viosfm run --stream` or `--follow` (stream_pipeline.h):
// the VIO's thread, the features beside it, the verification on the calling
// thread and the mapper on its own, over the selected frames.
#pragma once

#include <filesystem>
#include <optional>
#include <unordered_map>
#include <vector>

#include "viosfm/features/feature_extraction.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/euroc_follower.h"
#include "viosfm/io/frame_cache.h"
#include "viosfm/matching/incremental_pair_generator.h"
#include "viosfm/matching/pair_decider.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/pipeline/feature_prefetch.h"
#include "viosfm/pipeline/frame_ingest.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/settled_vio.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/pipeline/stream_inputs.h"
#include "viosfm/retrieval/incremental_retrieval.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/verified_pair_stream.h"
#include "viosfm/util/timer.h"

namespace viosfm {

// Everything the stream builds, for the stages after it.
struct StreamOutput {
  VioPoses vio;
  // The selected frames as mapped, in order, without their keypoints (the
  // mapper holds those; the points' colours come from the grey values
  // sampled when each frame's features were extracted).
  std::vector<MapperImage> images;
  BatchedMapperInput input;  // cameras, IMU, rig, readout (the frames: `images`)
  Reconstruction reconstruction;
  VerificationResult verification;
  BatchedMapperSummary stream_mapper_summary;
  FeatureExtractionSummary features;
  PipelineStreamSummary stream;
  // A followed recording: the recording as it came, and its frame selection;
  // its texture probe (on its first frames) and the rate and feature count
  // it settled.
  Sequence followed;
  FrameSelection followed_selection;
  PipelineSummary probe;
  double frame_rate_hz = 0.0;
  int max_num_features = 0;
  int max_image_size = 0;
};

// s of a followed recording's first images its texture probe looks at (the
// frames it probes spread over them): the recording's start stands for the
// whole, which does not exist yet. The selection waits for them.
constexpr double kFollowProbeWindowS = 10.0;

// The stream over the selected frames (see stream_pipeline.h).
class Stream {
 public:
  // A recorded dataset: `sequence` and its selected frames.
  Stream(const Sequence& sequence, const std::vector<size_t>& selected,
         const PipelineOptions& options, const RunFolder& folder, FrameCache* frame_cache,
         KeypointGreyValues* keypoint_values)
      : sequence_(&sequence),
        rig_(sequence.rig),
        root_(sequence.root),
        options_(options),
        verification_options_(options.EffectiveVerificationOptions()),
        folder_(folder),
        frame_cache_(frame_cache),
        keypoint_values_(keypoint_values),
        settled_(sequence.rig, sequence.root, options) {
    for (const size_t index : selected) {
      frame_queue_.Add(sequence.images[index]);
      paths_.push_back(sequence.images[index].path);
    }
    frame_queue_.Close();
    imu_.Add(sequence.imu);
  }
  // A recording being made, followed through `follower`.
  Stream(EurocFollower* follower, const PipelineOptions& options, const RunFolder& folder,
         FrameCache* frame_cache, KeypointGreyValues* keypoint_values)
      : follower_(follower),
        rig_(follower->header().rig),
        root_(follower->header().root),
        options_(options),
        verification_options_(options.EffectiveVerificationOptions()),
        folder_(folder),
        frame_cache_(frame_cache),
        keypoint_values_(keypoint_values),
        settled_(follower->header().rig, follower->header().root, options) {}

  StreamOutput Run(const Timer& stream_timer);

 private:
  // When the stream's parts ended, in s on the stream's clock.
  struct StreamTimes {
    double vio = 0.0;
    double last_frame = 0.0;
    double verification = 0.0;
    double mapper = 0.0;
  };

  // One selected frame as the verification holds it.
  struct Frame {
    PairImage image;  // its VIO pose and, while in memory, its features
    bool in_memory = false;
  };

  // The VIO's thread: the own VIO over the recorded dataset, a reader of
  // its selected frames for an external VIO, or the followed recording.
  void RunRecordedVio(const Timer& stream_timer, double* vio_seconds);
  void FollowRecording(const Timer& stream_timer, double* vio_seconds);
  // The frame's features (taken from beside the VIO, or extracted), then
  // the ingest step (frame_ingest.h), its pairs' generator and retrieval.
  void Ingest(const SequenceImage& image);
  // The database, its camera written.
  void OpenDatabase();
  // Frames' retrieved partners to the pair generator.
  void TakeRetrieved(std::vector<RetrievedFrame> results);
  // Every frame in and the pair generator told: the last frames'
  // retrieval, and the pairs still to decide.
  void FinishVerification();
  // The stream's summary figures.
  void TakeTimes(const StreamTimes& times);
  // Verifies the pairs of frame d with the frames before it.
  void Decide(size_t d, const std::vector<ProposedPair>& partners);
  // Decides every frame whose pairs are fixed.
  void DecideReady();
  // frames_[k].image with its features (read back from the database when
  // no longer in memory), normalised descriptors too when `normalised`.
  const PairImage& WithFeatures(size_t k, bool normalised);
  void ForgetFeaturesBefore(size_t k);
  // Once the VIO's rig is known: the ingest step, the verification's
  // decider, retrieval and pair generator.
  void SetUpVerification();
  // Every pair decided: the verification's result and summary.
  void TakeVerification(double verification_seconds);
  // The model so far, in OUT/live/ (the mapper's thread, after each batch).
  void WriteLiveModel(const Reconstruction& model, const MapperBatchStatistics& batch) const;

  const Sequence* sequence_ = nullptr;  // a recorded dataset
  EurocFollower* follower_ = nullptr;   // a recording being made
  const SensorRig rig_;
  const std::filesystem::path root_;
  // The run's options; a followed recording's texture probe settles their
  // frame rate and feature count before the first frame is queued.
  PipelineOptions options_;
  const VerificationOptions verification_options_;
  const RunFolder& folder_;
  FrameCache* frame_cache_;
  KeypointGreyValues* keypoint_values_;
  SettledVio settled_;
  FrameQueue frame_queue_;
  SharedImu imu_;
  std::vector<std::filesystem::path> paths_;  // the selected frames known up front

  std::optional<ColmapDatabase> database_;
  Camera camera_;
  VioSetup setup_;
  bool rolling_shutter_ = false;
  std::optional<FrameIngest> ingest_;  // once the VIO's rig is known
  std::optional<FeaturePrefetch> prefetch_;
  std::optional<PairDecider> decider_;
  std::optional<IncrementalRetrieval> retrieval_;
  VerifiedPairStream pair_stream_;
  std::vector<Frame> frames_;
  std::optional<IncrementalPairGenerator> pair_generator_;
  std::unordered_map<image_t, size_t> frame_of_image_;
  StreamOutput out_;
  double busy_seconds_ = 0.0;
  double recording_end_seconds_ = 0.0;  // a followed recording's last row
};

}  // namespace viosfm

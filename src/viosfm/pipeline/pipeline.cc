#include "viosfm/pipeline/pipeline.h"

#include <algorithm>
#include <iomanip>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "viosfm/io/dataset.h"
#include "viosfm/pipeline/feature_prefetch.h"
#include "viosfm/pipeline/run_common.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/pipeline/stage_dataset.h"
#include "viosfm/pipeline/stage_evaluation.h"
#include "viosfm/pipeline/stage_features.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_mapping.h"
#include "viosfm/pipeline/stage_outputs.h"
#include "viosfm/pipeline/stage_verification.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/pipeline/stream_pipeline.h"
#include "viosfm/pipeline/texture_probe.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

// The stage names, in order (summary.json "stages").
const std::vector<std::string> kStageNames = {
    "read_dataset", "vio",    "select_frames", "features",   "verification",
    "load_matches", "mapper", "colors",        "evaluation", "write_outputs"};

// When the frame selection does not need the VIO, the frames the features
// stage will take are known before it: only those stay decoded. viosfm's
// own VIO, which decodes every frame on one core, then has their features
// extracted beside it on another (feature_prefetch.h) when the run has more
// than one thread, unless the folder holds stored features (a resumed run
// extracts only what they lack).
void StartFeaturesBesideTheVio(const Sequence& sequence, const PipelineOptions& options,
                               const RunFolder& folder, FrameCache* frame_cache,
                               std::optional<FeaturePrefetch>* prefetch) {
  if (FrameSelectionUsesTrajectory(sequence, options.frame_selection)) return;
  const FrameSelection predicted = SelectFrames(sequence, options.frame_selection, nullptr);
  std::vector<std::filesystem::path> paths;
  for (const size_t index : predicted.kept) paths.push_back(sequence.images[index].path);
  frame_cache->RetainOnly(paths);
  if (options.UsesOwnVio() && options.num_threads > 1 &&
      !std::filesystem::exists(folder.path() / "database.db")) {
    prefetch->emplace(std::move(paths), options.EffectiveSiftOptions(), sequence.rig.camera,
                      frame_cache, kFeaturePrefetchBytes);
  }
}

// The VIO's parts of the summary, and the frames' selection.
void TakeVioAndFrames(const VioPoses& vio, const SelectedFrames& frames, PipelineSummary* summary) {
  summary->num_vio_segments = vio.num_segments();
  summary->vio_segment_rule = vio.segment_rule;
  summary->own_vio = vio.own_vio;
  summary->own_vio_summary = vio.own_vio_summary;
  summary->frame_selection = frames.selection;
  summary->num_frames_selected = frames.sequence.images.size();
  summary->num_frames_without_vio_pose = frames.num_without_vio_pose;
  summary->rolling_shutter_readout_s =
      frames.rolling_shutter.active() ? frames.rolling_shutter.readout_s : 0.0;
  summary->rolling_shutter_source = vio.rolling_shutter_source;
}

// The decoded frames the points' colours do not need leave the frame cache
// before the mapper, the run's largest stage: those whose keypoints' grey
// values the features stage sampled (every frame's, unless a frame was
// missing then).
void ReleaseFramesColoursDoNotNeed(const SelectedFrames& frames, const BatchedMapperInput& input,
                                   const KeypointGreyValues& keypoint_values,
                                   FrameCache* frame_cache) {
  std::vector<std::filesystem::path> still_needed;
  for (size_t i = 0; i < input.images.size(); ++i) {
    if (keypoint_values.Find(input.images[i].image_id) == nullptr) {
      still_needed.push_back(frames.sequence.images[i].path);
    }
  }
  frame_cache->RetainOnly(still_needed);
  ReturnFreedMemory();
}

}  // namespace

PipelineSummary RunPipeline(const PipelineOptions& requested) {
  if (requested.stream || requested.follow) return RunStreamPipeline(requested);
  // The options as asked for, until the texture probe settles the frame
  // rate and the feature count.
  PipelineOptions options = requested;
  PipelineSummary summary = StartRunSummary(options);
  Timer total_timer;
  total_timer.Start();
  StageClock clock(&summary.stages, kStageNames);
  const std::string vio_name = options.VioName();

  // A dataset path that names nothing leaves no output folder behind.
  CheckDatasetExists(options.dataset);
  // Locked while this run writes into it; an earlier run's outputs removed
  // (--overwrite), or its stored data checked against this run's inputs
  // before anything changes.
  const RunFolder folder(options);
  FrameCache frame_cache(kFrameCacheBytes);
  KeypointGreyValues keypoint_values;
  RunFingerprint fingerprint = FingerprintOfInputs(options);

  const Sequence sequence = clock.Run([&] {
    Sequence read = ReadDatasetStage(options, folder, &fingerprint);
    ResolveSettingsByPace(read, &frame_cache, &options, &summary);
    AddSettledRateAndFeatures(options, &fingerprint);
    return read;
  });
  summary.num_frames_in = sequence.images.size();

  std::optional<FeaturePrefetch> prefetch;
  StartFeaturesBesideTheVio(sequence, options, folder, &frame_cache, &prefetch);

  const VioPoses vio = clock.Run([&] {
    VioPoses poses = LoadVioPoses(sequence, options, &frame_cache);
    if (prefetch) {
      prefetch->Finish();
      VIOSFM_LOG(INFO) << "run: features of " << prefetch->num_extracted()
                       << " frames extracted beside the VIO (" << prefetch->peak_bytes() / (1 << 20)
                       << " MiB held at most)";
    }
    AddVioPosesToFingerprint(poses.world_from_body, poses.segments, &fingerprint);
    folder.CheckStoredData(fingerprint, /*complete=*/true);
    return poses;
  });
  summary.fingerprint = fingerprint.Hash();

  const SelectedFrames frames =
      clock.Run([&] { return SelectFramesStage(sequence, vio, options, vio_name, &frame_cache); });
  TakeVioAndFrames(vio, frames, &summary);

  FeaturesStageOutput features = clock.Run([&] {
    return ExtractFeaturesStage(frames, options, folder, fingerprint, &frame_cache,
                                &keypoint_values, prefetch ? &*prefetch : nullptr);
  });
  prefetch.reset();
  summary.features = features.summary;
  ReturnFreedMemory();

  const VerificationResult verification =
      clock.Run([&] { return VerifyPairsStage(frames, vio, options, &features.database); });
  summary.verification = verification.summary;
  ReturnFreedMemory();

  const BatchedMapperInput input = clock.Run([&] {
    return LoadMapperInputStage(frames, vio, verification, &features.database, &summary.vio_gaps);
  });
  if (summary.vio_gaps.num_gaps > 0) summary.num_vio_segments = summary.vio_gaps.num_segments;
  ReleaseFramesColoursDoNotNeed(frames, input, keypoint_values, &frame_cache);

  std::vector<Reconstruction> other_models;
  Reconstruction reconstruction = clock.Run(
      [&] { return MapStage(input, sequence, vio, options, &summary, nullptr, &other_models); });

  clock.Run([&] {
    ColorPointsStage(frames, input, options.show_progress, &keypoint_values, &frame_cache,
                     &reconstruction);
  });

  const TrajectoryEvaluation evaluation = clock.Run([&] {
    return EvaluateStage(sequence, frames, vio, input, reconstruction,
                         options.max_vio_time_difference_ns);
  });
  TakeEvaluation(evaluation, &summary);

  clock.Run([&] {
    WriteOutputsStage(options.output_folder, verification, reconstruction, frames, evaluation,
                      other_models);
  });

  // Every output on disk before summary.json says the run is complete (the
  // other files sync as they are written, util/file_util.h).
  features.database.SyncToDisk();
  FinishRunSummary(frame_cache, total_timer, folder, &summary);
  return summary;
}

}  // namespace viosfm

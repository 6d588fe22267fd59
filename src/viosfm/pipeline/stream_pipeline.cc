#include "viosfm/pipeline/stream_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/euroc_follower.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/kalibr.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/matching/incremental_pair_generator.h"
#include "viosfm/matching/pair_decider.h"
#include "viosfm/matching/pair_generator.h"
#include "viosfm/matching/pair_verification.h"
#include "viosfm/pipeline/feature_prefetch.h"
#include "viosfm/pipeline/frame_selection.h"
#include "viosfm/pipeline/run_common.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/run_folder.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/pipeline/stage_dataset.h"
#include "viosfm/pipeline/stage_evaluation.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_mapping.h"
#include "viosfm/pipeline/stage_outputs.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/pipeline/stream.h"
#include "viosfm/retrieval/incremental_retrieval.h"
#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sfm/batched_mapper.h"
#include "viosfm/sfm/verified_pair_stream.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/timer.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// The stage names, in order (summary.json "stages").
const std::vector<std::string> kStreamStageNames = {"read_dataset", "stream", "colors",
                                                    "evaluation", "write_outputs"};

// The dataset: a recorded one read whole, or a recording being made, whose
// calibration is known now and its rows as they come.
struct StreamSource {
  std::optional<Sequence> recorded;
  std::optional<EurocFollower> follower;
  std::optional<FrameSelection> selection;  // a recorded dataset's frames
};

StreamSource ReadStreamSource(const RunFolder& folder, FrameCache* frame_cache,
                              PipelineOptions* options, PipelineSummary* summary,
                              RunFingerprint* fingerprint) {
  StreamSource source;
  if (options->follow) {
    if (!IsEurocDatasetFolder(options->dataset)) {
      throw InputError(options->dataset.string(), 0,
                       "--follow: a EuRoC folder being recorded (mav0/cam0, mav0/imu0) is "
                       "followed; this is not one");
    }
    source.follower.emplace(options->dataset);
    ApplyCalibrationFiles(options->calibration, source.follower->mutable_header());
    return source;
  }
  source.recorded = ReadDatasetStage(*options, folder, fingerprint);
  ResolveSettingsByPace(*source.recorded, frame_cache, options, summary);
  AddSettledRateAndFeatures(*options, fingerprint);
  summary->num_frames_in = source.recorded->images.size();
  if (options->UsesOwnVio() && !source.recorded->has_imu()) {
    throw InputError(options->dataset.string(), 0,
                     "--stream: the stream runs viosfm's own VIO, which needs an IMU, and the "
                     "dataset has none; run the images alone without --stream");
  }
  if (options->UsesOwnVio() &&
      FrameSelectionUsesTrajectory(*source.recorded, options->frame_selection)) {
    throw InputError(options->dataset.string(), 0,
                     "--stream: the frame selection would need the own VIO's trajectory "
                     "(frame_selection.static_source), which a stream has only at its end; "
                     "select the static frames by the IMU, or run without --stream");
  }
  return source;
}

// The stream over the source's frames. A recorded dataset's frames are
// selected first (an external VIO's trajectory read for the selection when
// it asks); a followed recording's are selected as it grows.
StreamOutput RunStreamOverSource(const PipelineOptions& options, const RunFolder& folder,
                                 FrameCache* frame_cache, KeypointGreyValues* keypoint_values,
                                 StreamSource* source, RunFingerprint* fingerprint) {
  const Timer stream_timer;
  // What the database is made from, before it changes: the VIO's poses
  // (and a followed recording's files) once the VIO has ended.
  if (options.UsesOwnVio()) {
    fingerprint->Set("vio.poses", "pending: a streamed run writes them when its VIO ends");
  }
  if (source->follower) {
    fingerprint->Set("dataset.images", "pending: the recording is followed as it is made");
    folder.MarkIncomplete();
    folder.WriteRecords(*fingerprint, options.ToKeyValues());
    Stream stream(&*source->follower, options, folder, frame_cache, keypoint_values);
    return stream.Run(stream_timer);
  }
  const Sequence& recorded = *source->recorded;
  std::optional<Trajectory> external;
  if (!options.UsesOwnVio() && FrameSelectionUsesTrajectory(recorded, options.frame_selection)) {
    external = LoadVioTrajectory(recorded, options);
  }
  source->selection =
      SelectFrames(recorded, options.frame_selection, external ? &*external : nullptr);
  if (!source->selection->ok()) {
    throw InputError(options.dataset.string(), 0,
                     "no frames to reconstruct: " + source->selection->message);
  }
  std::vector<fs::path> paths;
  for (const size_t index : source->selection->kept) paths.push_back(recorded.images[index].path);
  frame_cache->RetainOnly(paths);
  folder.WriteRecords(*fingerprint, options.ToKeyValues());
  Stream stream(recorded, source->selection->kept, options, folder, frame_cache, keypoint_values);
  return stream.Run(stream_timer);
}

// A followed recording, now complete: as it came, with the rate and the
// feature count its texture probe settled.
void TakeFollowedRecording(StreamOutput* streamed, StreamSource* source, PipelineOptions* options,
                           PipelineSummary* summary, RunFingerprint* fingerprint) {
  source->recorded = std::move(streamed->followed);
  source->selection = streamed->followed_selection;
  summary->num_frames_in = source->recorded->images.size();
  summary->texture_probe = streamed->probe.texture_probe;
  summary->texture_probe_message = streamed->probe.texture_probe_message;
  options->frame_selection.target_rate_hz = streamed->frame_rate_hz;
  options->sift.max_num_features = streamed->max_num_features;
  options->sift.max_image_size = streamed->max_image_size;
  summary->frame_rate_hz = streamed->frame_rate_hz;
  summary->max_num_features = streamed->max_num_features;
  *fingerprint = FingerprintOfInputs(*options);
  AddSequenceToFingerprint(*source->recorded, fingerprint);
  AddSettledRateAndFeatures(*options, fingerprint);
}

// The stream's parts of the summary.
void TakeStreamOutput(StreamOutput* streamed, PipelineSummary* summary) {
  const VioPoses& vio = streamed->vio;
  summary->num_vio_segments = vio.num_segments();
  summary->vio_segment_rule = vio.segment_rule;
  summary->own_vio = vio.own_vio;
  summary->own_vio_summary = vio.own_vio_summary;
  summary->stream = streamed->stream;
  summary->features = streamed->features;
  summary->verification = streamed->verification.summary;
  summary->mapper = std::move(streamed->stream_mapper_summary);
  summary->rolling_shutter_readout_s = streamed->input.rolling_shutter_readout_s;
  summary->rolling_shutter_source = vio.rolling_shutter_source;
}

}  // namespace

PipelineSummary RunStreamPipeline(const PipelineOptions& requested) {
  PipelineOptions options = requested;
  options.stream = true;
  PipelineSummary summary = StartRunSummary(options);
  Timer total_timer;
  total_timer.Start();
  StageClock clock(&summary.stages, kStreamStageNames);
  const std::string vio_name = options.VioName();

  CheckDatasetExists(options.dataset);
  const RunFolder folder(options);
  if (fs::exists(folder.path() / "database.db")) {
    throw InputError((folder.path() / "database.db").string(), 0,
                     "a streamed run (--stream, --follow) starts afresh and does not resume: this "
                     "folder holds an earlier run's features and matches; re-run with --overwrite "
                     "to remove that run's outputs, or choose another --out");
  }
  // One arena a thread the run asks for: a lower peak for the same CPU (see
  // docs/benchmarks.md, section "The stream, and a recording followed").
  LimitMallocArenas(std::max(2, options.num_threads));
  FrameCache frame_cache(kFrameCacheBytes);
  KeypointGreyValues keypoint_values;
  RunFingerprint fingerprint = FingerprintOfInputs(options);

  StreamSource source = clock.Run(
      [&] { return ReadStreamSource(folder, &frame_cache, &options, &summary, &fingerprint); });
  StreamOutput streamed = clock.Run([&] {
    return RunStreamOverSource(options, folder, &frame_cache, &keypoint_values, &source,
                               &fingerprint);
  });
  if (source.follower) {
    TakeFollowedRecording(&streamed, &source, &options, &summary, &fingerprint);
  }
  const Sequence& sequence = *source.recorded;
  const VioPoses& vio = streamed.vio;
  AddVioPosesToFingerprint(vio.world_from_body, vio.segments, &fingerprint);
  folder.WriteRecords(fingerprint, options.ToKeyValues());
  summary.fingerprint = fingerprint.Hash();
  TakeStreamOutput(&streamed, &summary);

  // The frames as the stream took them: its selection, each frame with the
  // VIO pose it took (the VIO's poses settle as they end).
  const SelectedFrames frames =
      SelectedFramesOf(sequence, *source.selection, vio, options, vio_name, &frame_cache);
  summary.frame_selection = frames.selection;
  summary.num_frames_selected = frames.sequence.images.size();
  summary.num_frames_without_vio_pose = frames.num_without_vio_pose;
  FinishMapping(sequence, vio, options, &summary, &streamed.reconstruction);
  ReturnFreedMemory();

  BatchedMapperInput mapped = std::move(streamed.input);
  mapped.images = std::move(streamed.images);
  clock.Run([&] {
    ColorPointsStage(frames, mapped, options.show_progress, &keypoint_values, &frame_cache,
                     &streamed.reconstruction);
  });
  const TrajectoryEvaluation evaluation = clock.Run([&] {
    return EvaluateStage(sequence, frames, vio, mapped, streamed.reconstruction,
                         options.max_vio_time_difference_ns);
  });
  TakeEvaluation(evaluation, &summary);
  clock.Run([&] {
    WriteOutputsStage(options.output_folder, streamed.verification, streamed.reconstruction, frames,
                      evaluation);
  });

  // The database was synced and closed at the stream's end.
  FinishRunSummary(frame_cache, total_timer, folder, &summary);
  return summary;
}

}  // namespace viosfm

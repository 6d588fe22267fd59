#include "viosfm/pipeline/stage_evaluation.h"

#include <algorithm>

#include "viosfm/eval/gyro_check.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

// Ground truth is interpolated between two states at most this far apart (ns).
constexpr timestamp_ns_t kMaxGroundTruthGapNs = 50'000'000;

// The model's registered frames, in time order.
struct PosedFrames {
  std::vector<ModelFramePose> model_frames;
  Trajectory vio_registered;  // the input VIO at the posed frames that have a VIO pose
};

// The posed frames' trajectories (into `result`) and what the later steps
// need of them.
PosedFrames TakePosedFrames(const SelectedFrames& frames, const VioPoses& vio,
                            const BatchedMapperInput& input, const Reconstruction& reconstruction,
                            TrajectoryEvaluation* result) {
  PosedFrames posed;
  const Rigid3d cam_from_body = frames.sequence.rig.body_from_cam.Inverse();
  for (size_t i = 0; i < input.images.size(); ++i) {
    const image_t image_id = input.images[i].image_id;
    if (!reconstruction.ExistsImage(image_id)) continue;
    const Image& image = reconstruction.GetImage(image_id);
    if (!image.registered) continue;
    const timestamp_ns_t stamp = input.images[i].timestamp_ns;
    const Rigid3d world_from_cam = image.cam_from_world.Inverse();
    result->estimated_cam.poses.push_back({stamp, world_from_cam});
    result->estimated_body.poses.push_back({stamp, world_from_cam * cam_from_body});
    posed.model_frames.push_back({stamp, world_from_cam * cam_from_body, frames.vio_index[i]});
    if (const std::optional<size_t> pose_index = frames.vio_index[i]) {
      posed.vio_registered.poses.push_back(
          {stamp, vio.world_from_body.poses[*pose_index].world_from_frame});
    }
  }
  return posed;
}

// The model's rotations against the gyro (`rig`: the clock offset the run
// used), or the message why there is no check.
void CheckAgainstGyro(const Sequence& sequence, const SensorRig& rig,
                      TrajectoryEvaluation* result) {
  if (!sequence.has_imu()) {
    result->gyro_check_message = "no IMU";
    return;
  }
  try {
    const GyroCheckResult check =
        CheckRotationsAgainstGyro(result->estimated_cam, sequence.imu, rig, GyroCheckOptions{});
    PipelineGyroCheck& g = result->gyro_check.emplace();
    g.num_intervals = check.intervals.size();
    g.rmse_deg = check.error_deg.rmse;
    g.median_deg = check.error_deg.median;
    g.max_deg = check.error_deg.max;
    const auto worst =
        std::max_element(check.intervals.begin(), check.intervals.end(),
                         [](const auto& a, const auto& b) { return a.error_deg < b.error_deg; });
    const timestamp_ns_t start = check.intervals.front().from_ns;
    g.worst_from_s = static_cast<double>(worst->from_ns - start) * 1e-9;
    g.worst_to_s = static_cast<double>(worst->to_ns - start) * 1e-9;
    g.time_offset_ns = rig.cam_time_offset_ns;
  } catch (const InputError& error) {
    result->gyro_check_message = error.what();
  }
}

// The truth at every image of the recording, interpolated once; the
// selected frames' (their stamps are among the images', both in time
// order) into result->ground_truth_at_frames.
Trajectory GroundTruthAtImages(const Sequence& sequence,
                               const std::vector<timestamp_ns_t>& image_stamps,
                               const SelectedFrames& frames, TrajectoryEvaluation* result) {
  const Trajectory ground_truth = GroundTruthBodyTrajectory(sequence);
  Trajectory ground_truth_at_images;
  for (const timestamp_ns_t stamp : image_stamps) {
    if (const std::optional<Rigid3d> pose =
            InterpolatePose(ground_truth, stamp, kMaxGroundTruthGapNs)) {
      ground_truth_at_images.poses.push_back({stamp, *pose});
    }
  }
  auto truth = ground_truth_at_images.poses.begin();
  for (const SequenceImage& image : frames.sequence.images) {
    while (truth != ground_truth_at_images.poses.end() &&
           truth->timestamp_ns < image.timestamp_ns) {
      ++truth;
    }
    if (truth != ground_truth_at_images.poses.end() && truth->timestamp_ns == image.timestamp_ns) {
      result->ground_truth_at_frames.poses.push_back(*truth);
    }
  }
  return ground_truth_at_images;
}

// The metric figures beside result->estimate and result->vio.
struct MetricFigures {
  std::optional<MetricAccuracy> estimate;
  std::optional<MetricAccuracy> vio;
  std::optional<MetricAccuracy> all_frames;
};

// The estimate, the input VIO on the same frames where it posed them (when
// `judge_vio`) and the every-image trajectory against the ground truth.
MetricFigures JudgeAgainstGroundTruth(const Trajectory& vio_registered,
                                      const Trajectory& ground_truth_at_images, bool judge_vio,
                                      TrajectoryEvaluation* result) {
  MetricFigures metric;
  const EvaluationOptions& eval_options = result->options;
  const Trajectory& truth = result->ground_truth_at_frames;
  if (truth.size() < 3 || result->estimated_body.size() < 3 ||
      (judge_vio && vio_registered.size() < 3)) {
    VIOSFM_LOG(WARNING) << "run: no evaluation: " << truth.size() << " frames with ground truth, "
                        << result->estimated_body.size() << " registered (3 of each needed)";
    return metric;
  }
  try {
    result->estimate = EvaluateTrajectories(result->estimated_body, truth, eval_options);
    metric.estimate = EvaluateMetricAccuracy(result->estimated_body, truth, eval_options);
    if (judge_vio) {
      result->vio = EvaluateTrajectories(vio_registered, truth, eval_options);
      metric.vio = EvaluateMetricAccuracy(vio_registered, truth, eval_options);
    }
    if (result->all_frames.world_from_body.size() >= 3) {
      metric.all_frames = EvaluateMetricAccuracy(result->all_frames.world_from_body,
                                                 ground_truth_at_images, eval_options);
    }
  } catch (const InputError& error) {
    // A degenerate alignment (e.g. frames on a line) on valid input.
    VIOSFM_LOG(WARNING) << "run: no evaluation: " << error.what();
    result->estimate.reset();
    result->vio.reset();
  }
  return metric;
}

// summary.json's figures, when the estimate (and the VIO, if any) were judged.
std::optional<PipelineEvaluation> SummarizeEvaluation(const TrajectoryEvaluation& result,
                                                      const MetricFigures& metric, bool has_vio) {
  const std::optional<EvaluationResult>& evaluation = result.estimate;
  const std::optional<EvaluationResult>& evaluation_vio = result.vio;
  if (!evaluation || !metric.estimate || (has_vio && (!evaluation_vio || !metric.vio))) {
    return std::nullopt;
  }
  PipelineEvaluation e;
  e.metric = *metric.estimate;
  e.ate_rmse_m = evaluation->ate_translation_m.rmse;
  e.ate_median_m = evaluation->ate_translation_m.median;
  e.ate_mean_m = evaluation->ate_translation_m.mean;
  e.ate_max_m = evaluation->ate_translation_m.max;
  e.has_vio = has_vio;
  if (e.has_vio) {
    e.vio_metric = *metric.vio;
    e.vio_ate_rmse_m = evaluation_vio->ate_translation_m.rmse;
    e.vio_ate_median_m = evaluation_vio->ate_translation_m.median;
  }
  e.num_poses = evaluation->pairs.size();
  e.all_frames_metric = metric.all_frames;
  return e;
}

}  // namespace

TrajectoryEvaluation EvaluateStage(const Sequence& sequence, const SelectedFrames& frames,
                                   const VioPoses& vio, const BatchedMapperInput& input,
                                   const Reconstruction& reconstruction,
                                   timestamp_ns_t max_vio_time_difference_ns) {
  TrajectoryEvaluation result;
  const PosedFrames posed = TakePosedFrames(frames, vio, input, reconstruction, &result);
  std::vector<timestamp_ns_t> image_stamps;
  for (const SequenceImage& image : sequence.images) image_stamps.push_back(image.timestamp_ns);
  result.all_frames = PoseAllFrames(image_stamps, posed.model_frames, vio.world_from_body,
                                    vio.segments, max_vio_time_difference_ns);
  const AllFramePoseCounts& counts = result.all_frames.counts;
  VIOSFM_LOG(INFO) << "run: every image posed: " << counts.num_images - counts.num_unposed()
                   << " of " << counts.num_images << " images have a pose" << LogDetails() << " ("
                   << counts.ToString() << ")";
  // The own VIO's rig holds the time offset it estimated; an external
  // VIO's run uses the calibration's.
  CheckAgainstGyro(sequence, vio.own_vio_rig.value_or(frames.sequence.rig), &result);

  result.options.alignment = AlignmentMode::kSim3;
  result.options.association = AssociationMethod::kNearest;
  if (!sequence.has_ground_truth()) return result;
  const Trajectory ground_truth_at_images =
      GroundTruthAtImages(sequence, image_stamps, frames, &result);
  // A run without a VIO has none to judge.
  const MetricFigures metric = JudgeAgainstGroundTruth(posed.vio_registered, ground_truth_at_images,
                                                       /*judge_vio=*/!vio.absent, &result);
  result.summary = SummarizeEvaluation(result, metric, /*has_vio=*/!vio.absent);
  return result;
}

}  // namespace viosfm

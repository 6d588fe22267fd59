// Stage 9 of a `viosfm run` (pipeline.h): the estimated trajectories of the
// posed frames and of every image of the recording (all_frame_poses.h) and,
// with ground truth, their accuracy: the Sim(3)-aligned ATE
// (eval/traj_eval.h) and the metric figures (eval/metric_accuracy.h) of the
// estimate and of the input VIO on the same frames, and the metric figures
// of the every-image trajectory; with an IMU, the model's rotations against
// the gyro (eval/gyro_check.h) at the time offset the run used.
#pragma once

#include <optional>

#include "viosfm/eval/traj_eval.h"
#include "viosfm/pipeline/all_frame_poses.h"
#include "viosfm/pipeline/pipeline_summary.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/pipeline/stage_vio.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sfm/batched_mapper.h"

namespace viosfm {

struct TrajectoryEvaluation {
  Trajectory estimated_cam;                  // world_from_cam of the posed frames
  Trajectory estimated_body;                 // world_from_body of the posed frames
  Trajectory ground_truth_at_frames;         // at the selected frames (empty without ground truth)
  EvaluationOptions options;                 // Sim(3), nearest stamps
  std::optional<EvaluationResult> estimate;  // with ground truth on enough frames
  std::optional<EvaluationResult> vio;       // the input VIO on the same frames
  std::optional<PipelineEvaluation> summary;
  // Every image of the recording (all_frame_poses.h): the model's frames
  // and, between them, the VIO's relative motion.
  AllFramePoses all_frames;
  // With an IMU and one interval within its samples at least; else the
  // message says why there is none.
  std::optional<PipelineGyroCheck> gyro_check;
  std::string gyro_check_message;
};

// input.images[i] is frames.sequence.images[i] (LoadMapperInputStage).
// max_vio_time_difference_ns: how far an image's VIO pose may be from it
// (PipelineOptions).
TrajectoryEvaluation EvaluateStage(const Sequence& sequence, const SelectedFrames& frames,
                                   const VioPoses& vio, const BatchedMapperInput& input,
                                   const Reconstruction& reconstruction,
                                   timestamp_ns_t max_vio_time_difference_ns);

}  // namespace viosfm

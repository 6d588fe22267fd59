// Stage 10 of a `viosfm run` (pipeline.h): the output files (each written
// atomically): verification/pairs.csv and verification.json, model/ (COLMAP
// binary) and model_txt/, points.ply, trajectory_cam.tum,
// trajectory_body.tum, trajectory_body_all_frames.tum and
// trajectory_cam_all_frames.tum (every image of the recording,
// all_frame_poses.h), vio_body.tum, and with ground truth
// groundtruth_body.tum, eval.json and eval_vio.json (removed when this run
// has none, so nothing stale stays). summary.json is not written here: it
// is the run's last write (RunFolder::WriteSummary).
#pragma once

#include <filesystem>
#include <vector>

#include "viosfm/matching/verification_driver.h"
#include "viosfm/pipeline/stage_evaluation.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/scene/reconstruction.h"

namespace viosfm {

// The models the images could not join to the main one (`other_models`) go
// to models/1/, models/2/, ... (COLMAP binary).
void WriteOutputsStage(const std::filesystem::path& out, const VerificationResult& verification,
                       const Reconstruction& reconstruction, const SelectedFrames& frames,
                       const TrajectoryEvaluation& evaluation,
                       const std::vector<Reconstruction>& other_models = {});

}  // namespace viosfm

#include "viosfm/pipeline/stage_outputs.h"

#include "viosfm/eval/report.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/io/verification_report.h"

namespace viosfm {

namespace fs = std::filesystem;

void WriteOutputsStage(const fs::path& out, const VerificationResult& verification,
                       const Reconstruction& reconstruction, const SelectedFrames& frames,
                       const TrajectoryEvaluation& evaluation,
                       const std::vector<Reconstruction>& other_models) {
  const fs::path verification_folder = out / "verification";
  fs::create_directories(verification_folder);
  WritePairDecisionsCsv(verification_folder / "pairs.csv", verification.decisions);
  WriteVerificationJson(verification_folder / "verification.json", verification.summary,
                        verification.decisions);
  WriteColmapModelFolder(out / "model", reconstruction, ColmapModelFormat::kBinary);
  WriteColmapModelFolder(out / "model_txt", reconstruction, ColmapModelFormat::kText);
  WritePly(out / "points.ply", reconstruction);
  // The separate models of this run only: an earlier run's are gone.
  fs::remove_all(out / "models");
  for (size_t k = 0; k < other_models.size(); ++k) {
    WriteColmapModelFolder(out / "models" / std::to_string(k + 1), other_models[k],
                           ColmapModelFormat::kBinary);
  }
  WriteTumTrajectory(out / "trajectory_cam.tum", evaluation.estimated_cam);
  WriteTumTrajectory(out / "trajectory_body.tum", evaluation.estimated_body);
  WriteTumTrajectory(out / "trajectory_body_all_frames.tum", evaluation.all_frames.world_from_body);
  WriteTumTrajectory(out / "trajectory_cam_all_frames.tum",
                     BodyToCameraTrajectory(evaluation.all_frames.world_from_body,
                                            frames.sequence.rig.body_from_cam));
  WriteTumTrajectory(out / "vio_body.tum", frames.vio_at_frames);
  if (!evaluation.ground_truth_at_frames.empty()) {
    WriteTumTrajectory(out / "groundtruth_body.tum", evaluation.ground_truth_at_frames);
  } else {
    fs::remove(out / "groundtruth_body.tum");
  }
  const std::string gt_path = (out / "groundtruth_body.tum").string();
  if (evaluation.estimate) {
    WriteEvaluationJson(out / "eval.json", *evaluation.estimate, evaluation.options,
                        {(out / "trajectory_body.tum").string(), "tum", gt_path, "tum"});
  } else {
    fs::remove(out / "eval.json");
  }
  if (evaluation.estimate && evaluation.vio) {
    WriteEvaluationJson(out / "eval_vio.json", *evaluation.vio, evaluation.options,
                        {(out / "vio_body.tum").string(), "tum", gt_path, "tum"});
  } else {
    fs::remove(out / "eval_vio.json");
  }
}

}  // namespace viosfm

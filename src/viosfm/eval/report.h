// Human-readable and JSON reports of an evaluation.
#pragma once

#include <filesystem>
#include <string>

#include "viosfm/eval/gyro_check.h"
#include "viosfm/eval/traj_eval.h"

namespace viosfm {

// Where the trajectories came from, for the reports.
struct EvaluationInputs {
  std::string est_path;
  std::string est_format;
  std::string ref_path;
  std::string ref_format;
};

// A text table: inputs, association, alignment, ATE and RPE statistics.
std::string FormatEvaluationReport(const EvaluationResult& result, const EvaluationOptions& options,
                                   const EvaluationInputs& inputs);

// All numbers (full double precision), the options used and the inputs, as a
// JSON document:
//  {"inputs": {...}, "options": {...}, "num_est_poses", "num_ref_poses",
//   "association", "num_pairs", "alignment": {"mode", "num_pairs", "scale",
//   "rotation_wxyz", "translation"}, "ate": {"translation_m": stats,
//   "rotation_deg": stats}, "rpe_frames"/"rpe_distance": {"delta", "unit",
//   "all_pairs", "num_pairs", "translation_m", "rotation_deg"}}
// with stats = {"count", "rmse", "mean", "median", "std", "min", "max", "sse"}.
std::string EvaluationToJson(const EvaluationResult& result, const EvaluationOptions& options,
                             const EvaluationInputs& inputs);
// Writes EvaluationToJson atomically.
void WriteEvaluationJson(const std::filesystem::path& path, const EvaluationResult& result,
                         const EvaluationOptions& options, const EvaluationInputs& inputs);

// The gyro check (gyro_check.h) as a JSON document:
//  {"options": {"interval_s", "max_interval_factor", "fit_bias"},
//   "num_frames", "num_intervals", "num_without_imu", "num_gaps",
//   "time_offset_ns",
//   "bias_fitted", "num_bias_intervals", "gyro_bias_rad_s": [x, y, z], "error_deg": stats,
//   "intervals": [{"from_ns", "to_ns", "gyro_angle_deg", "error_deg"}]}
std::string GyroCheckToJson(const GyroCheckResult& result, const GyroCheckOptions& options);

}  // namespace viosfm

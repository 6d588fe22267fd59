#include "viosfm/pipeline/pipeline_options.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {

std::string OptionText(const VioSource& source) {
  return source ? "function" : "file";
}
void ParseOptionText(const std::string&, VioSource*) {
  throw InputError("a VIO source is given in code only");
}
std::string OptionText(const std::optional<SensorRig>& rig) {
  return rig ? "given in code" : "";
}
void ParseOptionText(const std::string&, std::optional<SensorRig>*) {
  throw InputError("a rig is given in code only");
}

VioFrame ParseVioFrame(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "body") return VioFrame::kBody;
  if (lower == "cam") return VioFrame::kCam;
  throw InputError("VIO frame '" + name + "': expected 'body' or 'cam'");
}

std::string VioFrameName(VioFrame frame) {
  return frame == VioFrame::kBody ? "body" : "cam";
}

std::string PipelineOptions::Validate() const {
  if (dataset.empty()) return "dataset: a dataset folder is required";
  if (output_folder.empty()) return "output_folder: an output folder is required";
  if (max_vio_time_difference_ns <= 0) return "max_vio_time_difference_ns must be positive";
  if (vio_max_gap_ns < 0) return "vio_max_gap_ns must be >= 0";
  if (!(own_vio_max_frame_interval_s > 0.0)) return "own_vio_max_frame_interval_s must be > 0";
  if (!(rolling_shutter_readout_s >= 0.0 && rolling_shutter_readout_s < 1.0)) {
    return "rolling_shutter.readout_s must be in [0, 1) s";
  }
  if (!(min_readout_evidence >= 1.0)) return "rolling_shutter.min_readout_evidence must be >= 1";
  if (const std::string error = vio_uncertainty.Validate(); !error.empty()) {
    return "vio_uncertainty." + error;
  }
  if (const std::string error = imu_scale.Validate(); !error.empty()) {
    return "imu_scale." + error;
  }
  if (const std::string error = dataset_checks.Validate(); !error.empty()) {
    return "dataset_checks." + error;
  }
  if (num_threads < 1) return "num_threads must be >= 1";
  if (stream_vocabulary_frames < 1) return "stream_vocabulary_frames must be >= 1";
  if ((stream || follow) && verification.pairs.mode == PairMode::kPairList) {
    return "stream: pairs.mode pair_list is not streamed";
  }
  if (!(follow_idle_s > 0.0) || !std::isfinite(follow_idle_s)) {
    return "follow_idle_s must be > 0 s";
  }
  if (follow && !UsesOwnVio()) {
    return "follow: a recording being made is followed with viosfm's own VIO (no "
           "vio_trajectory)";
  }
  if (follow && frame_selection.trim_static &&
      (frame_selection.static_source == StaticSource::kTrajectory ||
       frame_selection.static_source == StaticSource::kImuAndTrajectory)) {
    return "follow: a recording being made has its static frames found by the IMU "
           "(frame_selection.static_source auto or imu)";
  }
  if (follow && IsBagPath(dataset)) {
    return "follow: a EuRoC folder being recorded is followed, not a bag";
  }
  if (const std::string error = calibration.Validate(); !error.empty()) {
    return "calibration." + error;
  }
  if (const std::string error = frame_selection.Validate(); !error.empty()) {
    return "frame_selection." + error;
  }
  if (const std::string error = texture_probe.Validate(); !error.empty()) {
    return "texture_probe." + error;
  }
  if (const std::string error = feature_budget.Validate(); !error.empty()) {
    return "feature_budget." + error;
  }
  if (const std::string error = EffectiveSiftOptions().Validate(); !error.empty()) {
    return "sift." + error;
  }
  if (const std::string error = EffectiveVerificationOptions().Validate(); !error.empty()) {
    return "verification." + error;
  }
  if (const std::string error = EffectiveMapperOptions().Validate(); !error.empty()) {
    return "mapper." + error;
  }
  if (IsBagPath(dataset)) {
    if (const std::string error = EffectiveRosbagOptions().Validate(); !error.empty()) {
      return "rosbag." + error;
    }
  }
  return "";
}

RosbagDatasetOptions PipelineOptions::EffectiveRosbagOptions() const {
  RosbagDatasetOptions options = rosbag;
  if (options.extract_folder.empty()) options.extract_folder = output_folder / "bag";
  return options;
}

SiftOptions PipelineOptions::EffectiveSiftOptions() const {
  SiftOptions options = sift;
  options.num_threads = num_threads;
  return options;
}

VerificationOptions PipelineOptions::EffectiveVerificationOptions() const {
  VerificationOptions options = verification;
  options.num_threads = num_threads;
  options.retrieval.num_threads = num_threads;
  options.seed = seed;
  options.show_progress = show_progress;
  options.max_pose_time_difference_ns = max_vio_time_difference_ns;
  options.vio_uncertainty = vio_uncertainty;
  return options;
}

BatchedMapperOptions PipelineOptions::EffectiveMapperOptions() const {
  BatchedMapperOptions options = mapper;
  options.num_threads = num_threads;
  options.ba.num_threads = num_threads;
  options.show_progress = show_progress;
  options.vio_uncertainty = vio_uncertainty;
  return options;
}

PipelineOptions PipelineOptions::WithEffectiveStageOptions() const {
  PipelineOptions options = *this;
  options.sift = EffectiveSiftOptions();
  options.verification = EffectiveVerificationOptions();
  options.mapper = EffectiveMapperOptions();
  options.rosbag = EffectiveRosbagOptions();
  return options;
}

std::vector<std::pair<std::string, std::string>> PipelineOptions::ToKeyValues() const {
  return OptionsToKeyValues(WithEffectiveStageOptions());
}

std::vector<std::pair<std::string, std::string>> PipelineOptions::StoredDataKeyValues() const {
  return StoredDataOptions(WithEffectiveStageOptions());
}

std::string ApplySparseRecordingSettings(double rate_hz, PipelineOptions* options) {
  const FeatureBudgetOptions& budget = options->feature_budget;
  if (!budget.paper_settings_when_sparse || budget.features_per_second <= 0 || !(rate_hz > 0.0) ||
      budget.features_per_second / rate_hz < options->sift.max_num_features) {
    return "";
  }
  const PipelineOptions paper;
  options->verification.pairs.num_retrieval_neighbors =
      std::max(options->verification.pairs.num_retrieval_neighbors,
               paper.verification.pairs.num_retrieval_neighbors);
  options->mapper.ba.function_tolerance =
      std::min(options->mapper.ba.function_tolerance, paper.mapper.ba.function_tolerance);
  options->mapper.ba.max_linear_solver_iterations =
      std::max(options->mapper.ba.max_linear_solver_iterations,
               paper.mapper.ba.max_linear_solver_iterations);
  options->mapper.final_ba_max_refinements =
      std::max(options->mapper.final_ba_max_refinements, paper.mapper.final_ba_max_refinements);
  options->mapper.final_ba_refine_min_change =
      std::min(options->mapper.final_ba_refine_min_change, paper.mapper.final_ba_refine_min_change);
  std::ostringstream line;
  line << std::setprecision(3) << rate_hz << " frames a second, slower than the budget limits: N2 "
       << options->verification.pairs.num_retrieval_neighbors
       << " and the paper's bundle-adjustment settings";
  return line.str();
}

bool SettledBySparseRecording(const std::string& key) {
  return key == "verification.pairs.num_retrieval_neighbors" ||
         key == "mapper.ba.function_tolerance" || key == "mapper.ba.max_linear_solver_iterations" ||
         key == "mapper.final_ba_max_refinements" || key == "mapper.final_ba_refine_min_change";
}

void ApplyPreset(RunPreset preset, PipelineOptions* options) {
  const bool realtime = preset == RunPreset::kRealtime;
  const PipelineOptions paper;
  options->verification.pairs.num_temporal_neighbors =
      realtime ? 10 : paper.verification.pairs.num_temporal_neighbors;
  options->verification.pairs.num_retrieval_neighbors =
      realtime ? 5 : paper.verification.pairs.num_retrieval_neighbors;
  options->feature_budget.features_per_second =
      realtime ? 10000 : paper.feature_budget.features_per_second;
  options->sift.max_num_features = paper.sift.max_num_features;
  options->sift.max_image_size = paper.sift.max_image_size;
  options->verification.guided_matching = realtime || paper.verification.guided_matching;
  options->mapper.ba_window_batches = realtime ? 4 : paper.mapper.ba_window_batches;
  options->mapper.ba_window_max_held_views = realtime ? 5 : paper.mapper.ba_window_max_held_views;
  options->texture_probe.enable = realtime || paper.texture_probe.enable;
  options->mapper.ba.function_tolerance = realtime ? 3e-5 : paper.mapper.ba.function_tolerance;
  options->mapper.ba.max_linear_solver_iterations =
      realtime ? 100 : paper.mapper.ba.max_linear_solver_iterations;
  options->mapper.final_ba_max_refinements = realtime ? 1 : paper.mapper.final_ba_max_refinements;
  options->mapper.final_ba_refine_min_change =
      realtime ? 0.02 : paper.mapper.final_ba_refine_min_change;
}

}  // namespace viosfm

#include "viosfm/pipeline/pipeline_options.h"

#include <iomanip>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

std::string Text(double value) {
  std::ostringstream stream;
  stream << std::setprecision(10) << value;
  return stream.str();
}
std::string Text(bool value) {
  return value ? "true" : "false";
}
std::string JoinInts(const std::vector<int>& values) {
  std::string text;
  for (const int value : values) {
    if (!text.empty()) text += ',';
    text += std::to_string(value);
  }
  return text;
}

std::string Text(int value) {
  return std::to_string(value);
}
std::string Text(int64_t value) {
  return std::to_string(value);
}
std::string Text(uint64_t value) {
  return std::to_string(value);
}

}  // namespace

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
  if (const std::string error = vio_uncertainty.Validate(); !error.empty()) {
    return "vio_uncertainty." + error;
  }
  if (const std::string error = imu_scale.Validate(); !error.empty()) {
    return "imu_scale." + error;
  }
  if (num_threads < 1) return "num_threads must be >= 1";
  if (const std::string error = calibration.Validate(); !error.empty()) {
    return "calibration." + error;
  }
  if (const std::string error = frame_selection.Validate(); !error.empty()) {
    return "frame_selection." + error;
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
  if (HasRosbagExtension(dataset)) {
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

std::vector<std::pair<std::string, std::string>> PipelineOptions::ToKeyValues() const {
  std::vector<std::pair<std::string, std::string>> values = {
      {"dataset", dataset.string()},
      {"image_folder.timestamps_file", image_folder.timestamps_file.string()},
      {"image_folder.camera_yaml", image_folder.camera_yaml.string()},
      {"calibration.camchain", calibration.camchain.string()},
      {"calibration.imu", calibration.imu.string()},
      {"output_folder", output_folder.string()},
      {"vio.source", vio_source ? "function" : "file"},
      {"vio.trajectory", vio_trajectory.string()},
      {"vio.format", TrajectoryFormatName(vio_format)},
      {"vio.frame", VioFrameName(vio_frame)},
      {"vio.max_time_difference_ns", Text(int64_t{max_vio_time_difference_ns})},
      {"vio.max_gap_ns", Text(int64_t{vio_max_gap_ns})},
      {"frame_selection.trim_static", Text(frame_selection.trim_static)},
      {"frame_selection.static_source", StaticSourceName(frame_selection.static_source)},
      {"frame_selection.static_window_s", Text(frame_selection.static_window_s)},
      {"frame_selection.imu_lowpass_s", Text(frame_selection.imu_lowpass_s)},
      {"frame_selection.max_static_gyro_stddev_rad_s",
       Text(frame_selection.max_static_gyro_stddev_rad_s)},
      {"frame_selection.max_static_gyro_mean_rad_s",
       Text(frame_selection.max_static_gyro_mean_rad_s)},
      {"frame_selection.max_static_accel_stddev_m_s2",
       Text(frame_selection.max_static_accel_stddev_m_s2)},
      {"frame_selection.max_static_translation_m", Text(frame_selection.max_static_translation_m)},
      {"frame_selection.max_static_rotation_rad", Text(frame_selection.max_static_rotation_rad)},
      {"frame_selection.target_rate_hz", Text(frame_selection.target_rate_hz)},
  };
  if (HasRosbagExtension(dataset)) {
    const RosbagDatasetOptions r = EffectiveRosbagOptions();
    values.insert(values.end(), {{"rosbag.image_topic", r.image_topic},
                                 {"rosbag.imu_topic", r.imu_topic},
                                 {"rosbag.groundtruth_topic", r.groundtruth_topic},
                                 {"rosbag.camera_yaml", r.camera_yaml.string()},
                                 {"rosbag.imu_yaml", r.imu_yaml.string()},
                                 {"rosbag.rig", r.rig ? "given in code" : ""},
                                 {"rosbag.extract_folder", r.extract_folder.string()}});
  }
  for (const auto& [key, value] : vio_uncertainty.ToKeyValues()) {
    values.emplace_back("vio_uncertainty." + key, value);
  }
  // viosfm's own VIO runs only without a VIO source or file.
  if (!vio_source && vio_trajectory.empty()) {
    for (const auto& [key, value] : own_vio.ToKeyValues())
      values.emplace_back("own_vio." + key, value);
  }
  const SiftOptions s = EffectiveSiftOptions();
  values.insert(values.end(), {
                                  {"sift.max_num_features", Text(s.max_num_features)},
                                  {"sift.root_sift", Text(s.root_sift)},
                                  {"sift.peak_threshold", Text(s.peak_threshold)},
                                  {"sift.edge_threshold", Text(s.edge_threshold)},
                                  {"sift.num_octave_layers", Text(s.num_octave_layers)},
                                  {"sift.num_threads", Text(s.num_threads)},
                              });
  for (const auto& [key, value] : EffectiveVerificationOptions().ToKeyValues()) {
    values.emplace_back("verification." + key, value);
  }
  const BatchedMapperOptions m = EffectiveMapperOptions();
  values.insert(
      values.end(),
      {
          {"mapper.batch_size", Text(m.batch_size)},
          {"mapper.ba_window_batches", Text(m.ba_window_batches)},
          {"mapper.batch_ba_max_num_iterations", Text(m.batch_ba_max_num_iterations)},
          {"mapper.bridge_spans", JoinInts(m.bridge_spans)},
          {"mapper.bridge_max_matches", Text(m.bridge_max_matches)},
          {"mapper.tracks.min_track_length", Text(m.tracks.min_track_length)},
          {"mapper.tracks.conflict_policy",
           m.tracks.conflict_policy == TrackConflictPolicy::kSplit ? "split" : "drop"},
          {"mapper.triangulation.min_angle_deg", Text(m.triangulation.min_angle_deg)},
          {"mapper.triangulation.max_reprojection_error_px",
           Text(m.triangulation.max_reprojection_error_px)},
          {"mapper.triangulation.refine", Text(m.triangulation.refine)},
          {"mapper.triangulation.max_refine_iterations",
           Text(m.triangulation.max_refine_iterations)},
          {"mapper.ba.loss_scale_px", Text(m.ba.loss_scale_px)},
          {"mapper.ba.refine_intrinsics", Text(m.ba.refine_intrinsics)},
          {"mapper.ba.refine_principal_point", Text(m.ba.refine_principal_point)},
          {"mapper.ba.use_relative_pose_priors", Text(m.ba.use_relative_pose_priors)},
          {"mapper.ba.prior_alpha", Text(m.ba.prior_alpha)},
          {"mapper.ba.prior_beta", Text(m.ba.prior_beta)},
          {"mapper.ba.prior_rotation_sigma_rad", Text(m.ba.prior_rotation_sigma_rad)},
          {"mapper.ba.prior_translation_sigma_m", Text(m.ba.prior_translation_sigma_m)},
          {"mapper.ba.prior_weighting", PriorWeightingName(m.ba.prior_weighting)},
          {"mapper.ba.prior_loss_scale", Text(m.ba.prior_loss_scale)},
          {"mapper.ba.max_num_iterations", Text(m.ba.max_num_iterations)},
          {"mapper.ba.num_threads", Text(m.ba.num_threads)},
          {"mapper.ba.max_images_for_sparse_schur", Text(m.ba.max_images_for_sparse_schur)},
          {"mapper.ba.linear_solver", BaLinearSolverName(m.ba.linear_solver)},
          {"mapper.ba.function_tolerance", Text(m.ba.function_tolerance)},
          {"mapper.ba.gradient_tolerance", Text(m.ba.gradient_tolerance)},
          {"mapper.ba.parameter_tolerance", Text(m.ba.parameter_tolerance)},
          {"mapper.filter.max_reprojection_error_px", Text(m.filter.max_reprojection_error_px)},
          {"mapper.filter.min_triangulation_angle_deg", Text(m.filter.min_triangulation_angle_deg)},
          {"mapper.registration.verify_with_images", Text(m.registration.verify_with_images)},
          {"mapper.registration.pnp.max_error_px", Text(m.registration.pnp.max_error_px)},
          {"mapper.registration.pnp.min_num_inliers", Text(m.registration.pnp.min_num_inliers)},
          {"mapper.registration.min_num_correspondences",
           Text(m.registration.min_num_correspondences)},
          {"mapper.registration.min_predicted_inlier_ratio",
           Text(m.registration.min_predicted_inlier_ratio)},
          {"mapper.registration.min_reposing_inliers", Text(m.registration.min_reposing_inliers)},
          {"mapper.registration.break_sigmas", Text(m.registration.break_sigmas)},
          {"mapper.registration.min_supporting_observations",
           Text(m.registration.min_supporting_observations)},
          {"mapper.registration.support_max_error_px", Text(m.registration.support_max_error_px)},
          {"mapper.retriangulate", Text(m.retriangulate)},
          {"use_imu_scale", Text(use_imu_scale)},
          {"imu_scale.bias_window_s", Text(imu_scale.bias_window_s)},
          {"imu_scale.max_scale_sigma", Text(imu_scale.max_scale_sigma)},
          {"mapper.ba_after_each_batch", Text(m.ba_after_each_batch)},
          {"mapper.final_global_ba", Text(m.final_global_ba)},
          {"mapper.num_threads", Text(m.num_threads)},
          {"num_threads", Text(num_threads)},
          {"seed", Text(seed)},
          {"show_progress", Text(show_progress)},
      });
  return values;
}

}  // namespace viosfm

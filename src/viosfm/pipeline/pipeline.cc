#include "viosfm/pipeline/pipeline.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_map>

#include "viosfm/eval/report.h"
#include "viosfm/eval/traj_eval.h"
#include "viosfm/io/colmap_database.h"
#include "viosfm/io/colmap_model.h"
#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/verification_report.h"
#include "viosfm/pipeline/run_fingerprint.h"
#include "viosfm/pipeline/vio_input.h"
#include "viosfm/scene/reprojection.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/logging.h"
#include "viosfm/util/progress.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/timer.h"
#include "viosfm/vio/odometry.h"

#ifndef VIOSFM_VERSION
#define VIOSFM_VERSION "unknown"
#endif

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

// Ground truth is interpolated between two states at most this far apart (ns).
constexpr timestamp_ns_t kMaxGroundTruthGapNs = 50'000'000;

// The stage names, in order (summary.json "stages").
constexpr const char* kStageNames[] = {"read_dataset", "vio",          "select_frames", "features",
                                       "verification", "load_matches", "mapper",        "colors",
                                       "evaluation",   "write_outputs"};
constexpr int kNumStages = static_cast<int>(std::size(kStageNames));

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

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

double PeakMemoryMb() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

// The pose at `t`, interpolated (linear position, slerp rotation) between
// the two poses around it when they are at most max_gap apart.
std::optional<Rigid3d> InterpolatePose(const Trajectory& trajectory, timestamp_ns_t t,
                                       timestamp_ns_t max_gap) {
  const auto& poses = trajectory.poses;
  const auto it = std::lower_bound(
      poses.begin(), poses.end(), t,
      [](const StampedPose& pose, timestamp_ns_t stamp) { return pose.timestamp_ns < stamp; });
  if (it != poses.end() && it->timestamp_ns == t) return it->world_from_frame;
  if (it == poses.begin() || it == poses.end()) return std::nullopt;
  const StampedPose& before = *std::prev(it);
  const StampedPose& after = *it;
  if (after.timestamp_ns - before.timestamp_ns > max_gap) return std::nullopt;
  const double s = static_cast<double>(t - before.timestamp_ns) /
                   static_cast<double>(after.timestamp_ns - before.timestamp_ns);
  Rigid3d pose;
  pose.rotation = before.world_from_frame.rotation.slerp(s, after.world_from_frame.rotation);
  pose.translation =
      (1.0 - s) * before.world_from_frame.translation + s * after.world_from_frame.translation;
  return pose;
}

std::string SpanText(timestamp_ns_t first, timestamp_ns_t last) {
  std::ostringstream text;
  text << '[' << FormatNsAsSeconds(first, 3) << ", " << FormatNsAsSeconds(last, 3) << "] s";
  return text.str();
}

// Records each stage's wall-clock time and logs a heading for it.
class StageClock {
 public:
  explicit StageClock(std::vector<PipelineStageTime>* stages) : stages_(stages) {}
  void Begin(const std::string& name) {
    name_ = name;
    ++index_;
    VIOSFM_LOG(INFO) << "run [" << index_ << "/" << kNumStages << "] " << name;
    timer_.Start();
  }
  void End() {
    const double seconds = timer_.ElapsedSeconds();
    stages_->push_back({name_, seconds});
    VIOSFM_LOG(INFO) << "run [" << index_ << "/" << kNumStages << "] " << name_ << ": "
                     << std::fixed << std::setprecision(2) << seconds << " s";
  }

 private:
  std::vector<PipelineStageTime>* stages_;
  std::string name_;
  int index_ = 0;
  Timer timer_;
};

void WriteJsonFile(const fs::path& path, const std::string& text) {
  WriteFileAtomically(path, [&text](std::ostream& stream) { stream << text << "\n"; });
}

ordered_json MetricJson(const MetricAccuracy& m) {
  return {{"ate_sim3_rmse_m", m.ate_sim3_m.rmse},     {"ate_se3_rmse_m", m.ate_se3_m.rmse},
          {"ate_posyaw_rmse_m", m.ate_posyaw_m.rmse}, {"scale", m.scale},
          {"scale_error", m.scale_error()},           {"num_poses", m.num_poses}};
}

ordered_json StatsJson(const PipelineEvaluation& e) {
  ordered_json json;
  json["alignment"] = "sim3";
  json["ate_rmse_m"] = e.ate_rmse_m;
  json["ate_median_m"] = e.ate_median_m;
  json["ate_mean_m"] = e.ate_mean_m;
  json["ate_max_m"] = e.ate_max_m;
  json["vio_ate_rmse_m"] = e.vio_ate_rmse_m;
  json["vio_ate_median_m"] = e.vio_ate_median_m;
  json["num_poses"] = e.num_poses;
  json["metric"] = MetricJson(e.metric);
  json["vio_metric"] = MetricJson(e.vio_metric);
  return json;
}

// Mean grey value of each point over its observations in registered images.
void ColorPoints(const std::unordered_map<image_t, fs::path>& image_paths, bool show_progress,
                 Reconstruction* reconstruction) {
  std::unordered_map<point3D_t, std::pair<double, int>> sums;
  const std::vector<image_t> image_ids = reconstruction->RegImageIds();
  ProgressBar progress("colors", static_cast<int64_t>(image_ids.size()),
                       show_progress ? ProgressBar::Mode::kAuto : ProgressBar::Mode::kNever);
  for (const image_t image_id : image_ids) {
    const Image& image = reconstruction->GetImage(image_id);
    const auto path = image_paths.find(image_id);
    VIOSFM_CHECK(path != image_paths.end()) << "image " << image_id << " has no file";
    const GreyImage pixels = ReadGreyImage(path->second);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      // viosfm's pixel convention: pixel (x, y) has its centre at (x, y).
      const int x = std::clamp(static_cast<int>(std::lround(point2D.xy.x())), 0, pixels.width - 1);
      const int y = std::clamp(static_cast<int>(std::lround(point2D.xy.y())), 0, pixels.height - 1);
      auto& [sum, count] = sums[point2D.point3D_id];
      sum += pixels.at(x, y);
      ++count;
    }
    progress.Update();
  }
  progress.Finish();
  for (const point3D_t point3D_id : reconstruction->Point3DIds()) {
    const auto it = sums.find(point3D_id);
    if (it == sums.end() || it->second.second == 0) continue;
    const auto value = static_cast<uint8_t>(
        std::clamp(std::lround(it->second.first / it->second.second), 0L, 255L));
    reconstruction->GetPoint3D(point3D_id).color = Vector3ub::Constant(value);
  }
}

}  // namespace

bool IsEurocDatasetFolder(const fs::path& root) {
  return fs::is_directory(root / "mav0") ||
         (root.filename() == "mav0" && fs::is_directory(root / "cam0"));
}

std::string ViosfmVersion() {
  return VIOSFM_VERSION;
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

std::string PipelineSummary::ToString() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3);
  out << "frames: " << num_frames_in << " in, " << num_frames_selected << " selected ("
      << num_frames_without_vio_pose << " without a VIO pose), " << num_frames_registered
      << " registered (pose supported by the images), " << num_frames_vio_only
      << " placed by the VIO only, " << num_frames_unposed << " without a pose\n";
  out << "VIO: " << num_vio_segments << " segment(s), " << mapper.num_vio_segments_joined
      << " joined; " << mapper.num_reposed << " frame(s) re-posed from the images, "
      << mapper.num_registered_without_vio << " registered from the images without a VIO pose, "
      << mapper.num_vio_breaks << " VIO jump(s) found\n";
  if (!metric_scale.message.empty()) out << "metric scale: " << metric_scale.message << "\n";
  out << "pairs: " << verification.num_pairs << " candidates, " << verification.num_accepted
      << " accepted, " << verification.num_vio_rejected << " rejected by VIO, "
      << verification.num_ransac_rejected << " by RANSAC, " << verification.num_no_matches
      << " without matches\n";
  out << "points: " << num_points << ", observations " << num_observations << ", mean track length "
      << mean_track_length << ", mean reprojection error " << mean_reprojection_error_px << " px\n";
  if (evaluation) {
    out << "ATE (Sim(3), " << evaluation->num_poses << " poses): RMSE " << evaluation->ate_rmse_m
        << " m, median " << evaluation->ate_median_m << " m; input VIO RMSE "
        << evaluation->vio_ate_rmse_m << " m, median " << evaluation->vio_ate_median_m << " m\n";
    out << "metric: " << FormatMetricAccuracy(evaluation->metric) << "\n";
    out << "input VIO: " << FormatMetricAccuracy(evaluation->vio_metric) << "\n";
    out << std::fixed << std::setprecision(3);
  } else {
    out << "ATE: no ground truth\n";
  }
  out << std::setprecision(1) << "time: " << total_seconds << " s (";
  for (size_t i = 0; i < stages.size(); ++i) {
    out << (i > 0 ? ", " : "") << stages[i].name << " " << stages[i].seconds;
  }
  out << "), peak memory " << peak_memory_mb << " MB\n";
  out << "output: " << output_folder.string()
      << " (model/, model_txt/, points.ply, trajectory_body.tum, summary.json)";
  return out.str();
}

std::string PipelineSummaryToJson(const PipelineSummary& s) {
  ordered_json json;
  json["viosfm_version"] = ViosfmVersion();
  json["dataset"] = s.dataset;
  json["started_utc"] = s.started_utc;
  json["frames"] = {{"in", s.num_frames_in},
                    {"selected", s.num_frames_selected},
                    {"without_vio_pose", s.num_frames_without_vio_pose},
                    {"registered", s.num_frames_registered},
                    {"vio_only", s.num_frames_vio_only},
                    {"unposed", s.num_frames_unposed},
                    {"reposed_from_images", s.mapper.num_reposed},
                    {"registered_without_vio", s.mapper.num_registered_without_vio}};
  json["imu_scale"] = {{"estimated", s.metric_scale.estimated},
                       {"usable", s.metric_scale.imu.usable},
                       {"imu_scale", s.metric_scale.imu.scale},
                       {"imu_scale_sigma", s.metric_scale.imu.scale_sigma},
                       {"applied_scale", s.metric_scale.applied_scale},
                       {"message", s.metric_scale.message}};
  json["vio"] = {{"segments", s.num_vio_segments},
                 {"segments_joined", s.mapper.num_vio_segments_joined},
                 {"segment_rule", s.vio_segment_rule},
                 {"jumps_found", s.mapper.num_vio_breaks}};
  ordered_json unposed = ordered_json::array();
  for (const MapperFrameStatus& frame : s.mapper.frames) {
    if (!frame.reason.empty()) {
      unposed.push_back({{"image_id", frame.image_id}, {"reason", frame.reason}});
    }
  }
  json["unposed_frames"] = unposed;
  json["pairs"] = {{"candidates", s.verification.num_pairs},
                   {"accepted", s.verification.num_accepted},
                   {"vio_rejected", s.verification.num_vio_rejected},
                   {"ransac_rejected", s.verification.num_ransac_rejected},
                   {"no_matches", s.verification.num_no_matches}};
  json["points"] = s.num_points;
  json["observations"] = s.num_observations;
  json["mean_track_length"] = s.mean_track_length;
  json["mean_reprojection_error_px"] = s.mean_reprojection_error_px;
  json["relative_pose_priors"] = {{"consecutive", s.mapper.num_consecutive_priors},
                                  {"bridging", s.mapper.num_bridging_priors}};
  ordered_json batches = ordered_json::array();
  for (const MapperBatchStatistics& batch : s.mapper.batches) {
    batches.push_back({{"index", batch.batch_index},
                       {"images", batch.num_images},
                       {"registered_total", batch.num_registered_total},
                       {"points_total", batch.num_points_total},
                       {"mean_reprojection_error_px", batch.mean_reprojection_error_px},
                       {"seconds_ba", batch.seconds_ba},
                       {"ba_iterations", batch.num_ba_iterations},
                       {"ba_solver", BaLinearSolverName(batch.ba_linear_solver)}});
  }
  json["batches"] = batches;
  ordered_json stages = ordered_json::array();
  for (const PipelineStageTime& stage : s.stages) {
    stages.push_back({{"name", stage.name}, {"seconds", stage.seconds}});
  }
  json["stages"] = stages;
  json["total_seconds"] = s.total_seconds;
  json["peak_memory_mb"] = s.peak_memory_mb;
  if (s.evaluation) json["eval"] = StatsJson(*s.evaluation);
  json["options_file"] = "options.json";
  json["fingerprint"] = s.fingerprint;
  return json.dump(2);
}

Sequence ReadPipelineDataset(const fs::path& dataset, const ImageFolderOptions& image_folder,
                             const CalibrationFiles& calibration) {
  if (!fs::is_directory(dataset)) {
    throw InputError(dataset.string(), 0, "dataset folder not found");
  }
  Sequence sequence;
  if (IsEurocDatasetFolder(dataset)) {
    EurocReadOptions options;
    options.require_imu = false;  // the IMU only helps frame selection
    sequence = ReadEurocDataset(dataset, options);
  } else {
    if (const std::string error = image_folder.Validate(); !error.empty()) {
      throw InputError(dataset.string(), 0,
                       "not a EuRoC dataset (no mav0/), so read as an image folder: " + error +
                           " (give the camera)");
    }
    sequence = ReadImageFolder(dataset, image_folder);
  }
  if (sequence.images.empty()) {
    throw InputError(dataset.string(), 0, "the dataset has no images");
  }
  ApplyCalibrationFiles(calibration, &sequence);
  return sequence;
}

PipelineSummary RunPipeline(const PipelineOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid run options: " + error);
  }
  Timer total_timer;
  PipelineSummary summary;
  summary.started_utc = UtcNow();
  summary.dataset = options.dataset.string();
  summary.output_folder = options.output_folder;
  StageClock clock(&summary.stages);
  const fs::path out = options.output_folder;
  const std::string vio_name = options.vio_source || options.vio_trajectory.empty()
                                   ? std::string("the VIO")
                                   : options.vio_trajectory.string();

  // The folder: locked while this run writes into it; an earlier run's
  // outputs removed (--overwrite) or its stored data checked against this
  // run's inputs before anything changes.
  fs::create_directories(out);
  const FolderLock lock(out, "another viosfm run");
  if (options.overwrite) {
    RemoveRunOutputs(options);
  } else {
    RemoveAtomicWriteLeftovers(options);
  }

  // 1. Dataset.
  clock.Begin("read_dataset");
  RunFingerprint fingerprint = FingerprintOfInputs(options);
  CheckStoredRunData(out, fingerprint, /*complete=*/false);
  // Before the first write into the folder (a bag's images, the own VIO's
  // output): the folder is incomplete until summary.json is written again,
  // last. A refused run leaves an earlier run's complete folder as it was.
  const auto mark_incomplete = [&out] { fs::remove(out / "summary.json"); };
  Sequence sequence;
  if (HasRosbagExtension(options.dataset)) {
    mark_incomplete();
    sequence = ReadRosbagDataset(options.dataset, options.EffectiveRosbagOptions());
    ApplyCalibrationFiles(options.calibration, &sequence);
  } else {
    sequence = ReadPipelineDataset(options.dataset, options.image_folder, options.calibration);
  }
  AddSequenceToFingerprint(sequence, &fingerprint);
  CheckStoredRunData(out, fingerprint, /*complete=*/false);
  mark_incomplete();
  summary.num_frames_in = sequence.images.size();
  VIOSFM_LOG(INFO) << "run: " << sequence.images.size() << " images"
                   << (sequence.has_imu() ? ", IMU" : "")
                   << (sequence.has_ground_truth() ? ", ground truth" : "") << " in "
                   << options.dataset.string();
  clock.End();

  // 2. VIO trajectory of the whole sequence.
  clock.Begin("vio");
  const VioPoses vio_poses = LoadVioPoses(sequence, options);
  const Trajectory& vio = vio_poses.world_from_body;
  AddVioPosesToFingerprint(vio, vio_poses.segments, &fingerprint);
  CheckStoredRunData(out, fingerprint, /*complete=*/true);
  summary.fingerprint = fingerprint.Hash();
  summary.num_vio_segments = vio_poses.num_segments();
  summary.vio_segment_rule = vio_poses.segment_rule;
  VIOSFM_LOG(INFO) << "run: " << vio.size() << " VIO poses over "
                   << SpanText(vio.poses.front().timestamp_ns, vio.poses.back().timestamp_ns)
                   << " in " << vio_poses.num_segments() << " segment(s)";
  clock.End();

  // 3. Frames: static trimming, downsampling, and a VIO pose for each.
  clock.Begin("select_frames");
  summary.frame_selection = SelectFrames(sequence, options.frame_selection, &vio);
  if (!summary.frame_selection.ok()) {
    throw InputError(options.dataset.string(), 0,
                     "no frames to reconstruct: " + summary.frame_selection.message);
  }
  Sequence selected = sequence;
  selected.images.clear();
  // Per selected frame: the index of its VIO pose, if any.
  std::vector<std::optional<size_t>> vio_index_of_frame;
  Trajectory vio_at_frames;  // world_from_body at the selected frames with a VIO pose
  for (const size_t index : summary.frame_selection.kept) {
    const SequenceImage& image = sequence.images[index];
    const std::optional<size_t> pose_index =
        NearestVioPose(vio, image.timestamp_ns, options.max_vio_time_difference_ns);
    selected.images.push_back(image);
    vio_index_of_frame.push_back(pose_index);
    if (pose_index) {
      vio_at_frames.poses.push_back({image.timestamp_ns, vio.poses[*pose_index].world_from_frame});
    } else {
      ++summary.num_frames_without_vio_pose;
    }
  }
  if (vio_at_frames.size() < 2) {
    throw InputError(
        vio_name, 0,
        "the VIO poses " + SpanText(vio.poses.front().timestamp_ns, vio.poses.back().timestamp_ns) +
            " do not overlap the selected images " +
            SpanText(sequence.images.front().timestamp_ns, sequence.images.back().timestamp_ns) +
            " in time: " + std::to_string(vio_at_frames.size()) + " of " +
            std::to_string(summary.frame_selection.kept.size()) + " images have a pose within " +
            FormatNsAsSeconds(options.max_vio_time_difference_ns, 3) +
            " s (at least 2 are needed)");
  }
  if (summary.num_frames_without_vio_pose > 0) {
    VIOSFM_LOG(WARNING) << "run: " << summary.num_frames_without_vio_pose << " of "
                        << selected.images.size() << " selected frames have no VIO pose within "
                        << FormatNsAsSeconds(options.max_vio_time_difference_ns, 3)
                        << " s (VIO not initialised, lost or re-initialising): they are "
                           "registered from the images where these allow";
  }
  summary.num_frames_selected = selected.images.size();
  VIOSFM_LOG(INFO) << "run: " << summary.frame_selection.message << "; "
                   << selected.images.size() - summary.num_frames_without_vio_pose
                   << " frames with a VIO pose";
  clock.End();

  // 4. Features into OUT/database.db (resumable).
  clock.Begin("features");
  const std::vector<std::pair<std::string, std::string>> key_values = options.ToKeyValues();
  // What the database's content is made from, before the database changes.
  WriteJsonFile(out / "fingerprint.json", RunFingerprintToJson(fingerprint));
  {
    ordered_json json = ordered_json::object();
    for (const auto& [key, value] : key_values) json[key] = value;
    WriteJsonFile(out / "options.json", json.dump(2));
  }
  ColmapDatabase database = ColmapDatabase::Open(out / "database.db");
  summary.features =
      ExtractFeatures(selected, options.EffectiveSiftOptions(), &database, options.show_progress);
  VIOSFM_LOG(INFO) << "run: features " << summary.features.ToString();
  clock.End();

  // 5. Pairs and the two-step verification (resumable).
  clock.Begin("verification");
  const VerificationResult verification = RunVerification(
      selected, vio, &database, options.EffectiveVerificationOptions(), vio_poses.segments);
  summary.verification = verification.summary;
  VIOSFM_LOG(INFO) << "run: verification " << FormatVerificationSummary(verification.summary);
  clock.End();

  // 6. Mapper input: images, keypoints, VIO camera poses, inlier matches.
  clock.Begin("load_matches");
  BatchedMapperInput input;
  std::unordered_map<image_t, fs::path> image_paths;
  std::unordered_map<image_t, timestamp_ns_t> image_stamps;
  std::map<camera_t, bool> camera_ids;
  for (size_t i = 0; i < selected.images.size(); ++i) {
    const SequenceImage& image = selected.images[i];
    const std::string name = DatabaseImageName(image);
    const std::optional<DatabaseImage> row = database.ReadImageWithName(name);
    VIOSFM_CHECK(row.has_value()) << "image " << name << " missing after feature extraction";
    MapperImage mapper_image;
    mapper_image.image_id = row->image_id;
    mapper_image.camera_id = row->camera_id;
    mapper_image.name = name;
    mapper_image.timestamp_ns = image.timestamp_ns;
    mapper_image.keypoints = database.ReadKeypoints(row->image_id);
    if (const std::optional<size_t> pose_index = vio_index_of_frame[i]) {
      mapper_image.vio_cam_from_world =
          (vio.poses[*pose_index].world_from_frame * selected.rig.body_from_cam).Inverse();
      mapper_image.vio_odometer = vio_poses.odometers[*pose_index];
    }
    image_paths.emplace(row->image_id, image.path);
    image_stamps.emplace(row->image_id, image.timestamp_ns);
    camera_ids[row->camera_id] = true;
    input.images.push_back(std::move(mapper_image));
  }
  for (const auto& [camera_id, unused] : camera_ids) {
    input.cameras.push_back(database.ReadCamera(camera_id));
  }
  size_t num_inlier_matches = 0;
  for (const PairDecision& decision : verification.decisions) {
    if (!decision.accepted) continue;
    ImagePairMatches pair;
    pair.image_id1 = decision.image_id1;
    pair.image_id2 = decision.image_id2;
    pair.matches =
        database.ReadTwoViewGeometry(decision.image_id1, decision.image_id2).inlier_matches;
    num_inlier_matches += pair.matches.size();
    input.verified_pairs.push_back(std::move(pair));
  }
  VIOSFM_LOG(INFO) << "run: " << input.verified_pairs.size() << " accepted pairs, "
                   << num_inlier_matches << " inlier matches";
  clock.End();

  // 7. Batched incremental mapping.
  clock.Begin("mapper");
  Reconstruction reconstruction =
      RunBatchedMapper(input, options.EffectiveMapperOptions(), &summary.mapper);
  VIOSFM_LOG(INFO) << "run: mapper " << summary.mapper.ToString();
  if (options.use_imu_scale) {
    summary.metric_scale = ApplyImuMetricScale(
        sequence, vio_poses.own_vio_rig.value_or(sequence.rig), options.vio_uncertainty.scale_sigma,
        options.imu_scale, &reconstruction);
    VIOSFM_LOG(INFO) << "run: metric scale: " << summary.metric_scale.message;
  }
  summary.num_frames_registered = static_cast<size_t>(summary.mapper.num_supported);
  summary.num_frames_vio_only = static_cast<size_t>(summary.mapper.num_vio_only);
  summary.num_frames_unposed = static_cast<size_t>(summary.mapper.num_unposed);
  for (size_t i = 0; i < summary.mapper.frames.size(); ++i) {
    const MapperFrameStatus& frame = summary.mapper.frames[i];
    if (frame.reason.empty()) continue;
    VIOSFM_LOG(WARNING) << "run: no pose for " << input.images[i].name << ": " << frame.reason;
  }
  summary.num_points = reconstruction.NumPoints3D();
  summary.num_observations = reconstruction.ComputeNumObservations();
  summary.mean_track_length = reconstruction.ComputeMeanTrackLength();
  summary.mean_reprojection_error_px = UpdateReprojectionErrors(&reconstruction);
  clock.End();

  // 8. Point colours.
  clock.Begin("colors");
  ColorPoints(image_paths, options.show_progress, &reconstruction);
  clock.End();

  // 9. Trajectories and evaluation.
  clock.Begin("evaluation");
  Trajectory estimated_cam;   // world_from_cam of the posed frames
  Trajectory estimated_body;  // world_from_body
  Trajectory vio_registered;  // the input VIO at the posed frames that have a VIO pose
  const Rigid3d cam_from_body = selected.rig.body_from_cam.Inverse();
  for (size_t i = 0; i < input.images.size(); ++i) {
    const image_t image_id = input.images[i].image_id;
    if (!reconstruction.ExistsImage(image_id)) continue;
    const Image& image = reconstruction.GetImage(image_id);
    if (!image.registered) continue;
    const timestamp_ns_t stamp = image_stamps.at(image_id);
    const Rigid3d world_from_cam = image.cam_from_world.Inverse();
    estimated_cam.poses.push_back({stamp, world_from_cam});
    estimated_body.poses.push_back({stamp, world_from_cam * cam_from_body});
    if (const std::optional<size_t> pose_index = vio_index_of_frame[i]) {
      vio_registered.poses.push_back({stamp, vio.poses[*pose_index].world_from_frame});
    }
  }
  Trajectory ground_truth_at_frames;
  std::optional<EvaluationResult> evaluation;
  std::optional<EvaluationResult> evaluation_vio;
  std::optional<MetricAccuracy> metric;
  std::optional<MetricAccuracy> vio_metric;
  EvaluationOptions eval_options;
  eval_options.alignment = AlignmentMode::kSim3;
  eval_options.association = AssociationMethod::kNearest;
  if (sequence.has_ground_truth()) {
    const Trajectory ground_truth = GroundTruthBodyTrajectory(sequence);
    for (const SequenceImage& image : selected.images) {
      if (const std::optional<Rigid3d> pose =
              InterpolatePose(ground_truth, image.timestamp_ns, kMaxGroundTruthGapNs)) {
        ground_truth_at_frames.poses.push_back({image.timestamp_ns, *pose});
      }
    }
    if (ground_truth_at_frames.size() >= 3 && estimated_body.size() >= 3 &&
        vio_registered.size() >= 3) {
      try {
        evaluation = EvaluateTrajectories(estimated_body, ground_truth_at_frames, eval_options);
        evaluation_vio = EvaluateTrajectories(vio_registered, ground_truth_at_frames, eval_options);
        metric = EvaluateMetricAccuracy(estimated_body, ground_truth_at_frames, eval_options);
        vio_metric = EvaluateMetricAccuracy(vio_registered, ground_truth_at_frames, eval_options);
      } catch (const InputError& error) {
        // A degenerate alignment (e.g. frames on a line) on valid input.
        VIOSFM_LOG(WARNING) << "run: no evaluation: " << error.what();
        evaluation.reset();
        evaluation_vio.reset();
      }
    } else {
      VIOSFM_LOG(WARNING) << "run: no evaluation: " << ground_truth_at_frames.size()
                          << " frames with ground truth, " << estimated_body.size()
                          << " registered (3 of each needed)";
    }
  }
  if (evaluation && evaluation_vio && metric && vio_metric) {
    PipelineEvaluation e;
    e.metric = *metric;
    e.vio_metric = *vio_metric;
    e.ate_rmse_m = evaluation->ate_translation_m.rmse;
    e.ate_median_m = evaluation->ate_translation_m.median;
    e.ate_mean_m = evaluation->ate_translation_m.mean;
    e.ate_max_m = evaluation->ate_translation_m.max;
    e.vio_ate_rmse_m = evaluation_vio->ate_translation_m.rmse;
    e.vio_ate_median_m = evaluation_vio->ate_translation_m.median;
    e.num_poses = evaluation->pairs.size();
    summary.evaluation = e;
  }
  clock.End();

  // 10. Outputs; summary.json last.
  clock.Begin("write_outputs");
  const fs::path verification_folder = out / "verification";
  fs::create_directories(verification_folder);
  WritePairDecisionsCsv(verification_folder / "pairs.csv", verification.decisions);
  WriteVerificationJson(verification_folder / "verification.json", verification.summary,
                        verification.decisions);
  WriteColmapModelFolder(out / "model", reconstruction, ColmapModelFormat::kBinary);
  WriteColmapModelFolder(out / "model_txt", reconstruction, ColmapModelFormat::kText);
  WritePly(out / "points.ply", reconstruction);
  WriteTumTrajectory(out / "trajectory_cam.tum", estimated_cam);
  WriteTumTrajectory(out / "trajectory_body.tum", estimated_body);
  WriteTumTrajectory(out / "vio_body.tum", vio_at_frames);
  if (!ground_truth_at_frames.empty()) {
    WriteTumTrajectory(out / "groundtruth_body.tum", ground_truth_at_frames);
  } else {
    fs::remove(out / "groundtruth_body.tum");
  }
  if (evaluation && evaluation_vio) {
    const std::string gt_path = (out / "groundtruth_body.tum").string();
    WriteEvaluationJson(out / "eval.json", *evaluation, eval_options,
                        {(out / "trajectory_body.tum").string(), "tum", gt_path, "tum"});
    WriteEvaluationJson(out / "eval_vio.json", *evaluation_vio, eval_options,
                        {(out / "vio_body.tum").string(), "tum", gt_path, "tum"});
  } else {
    fs::remove(out / "eval.json");
    fs::remove(out / "eval_vio.json");
  }
  clock.End();

  summary.total_seconds = total_timer.ElapsedSeconds();
  summary.peak_memory_mb = PeakMemoryMb();
  WriteJsonFile(out / "summary.json", PipelineSummaryToJson(summary));
  return summary;
}

}  // namespace viosfm

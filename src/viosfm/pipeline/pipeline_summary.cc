#include "viosfm/pipeline/pipeline_summary.h"

#include <algorithm>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "viosfm/matching/verification_driver.h"

#ifndef VIOSFM_VERSION
#define VIOSFM_VERSION "unknown"
#endif

namespace viosfm {
namespace {

using ordered_json = nlohmann::ordered_json;

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
  if (e.has_vio) {
    json["vio_ate_rmse_m"] = e.vio_ate_rmse_m;
    json["vio_ate_median_m"] = e.vio_ate_median_m;
  }
  json["num_poses"] = e.num_poses;
  json["metric"] = MetricJson(e.metric);
  if (e.has_vio) json["vio_metric"] = MetricJson(e.vio_metric);
  if (e.all_frames_metric) json["all_frames_metric"] = MetricJson(*e.all_frames_metric);
  return json;
}

}  // namespace

std::string ViosfmVersion() {
  return VIOSFM_VERSION;
}

std::string PipelineSummary::ToString() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3);
  out << "frames: " << num_frames_in << " in, " << num_frames_selected << " selected ("
      << num_frames_without_vio_pose << " without a VIO pose); " << num_frames_registered
      << " registered by the images, " << num_frames_vio_only << " placed by the VIO only, "
      << num_frames_unposed << " unposed\n";
  if (mapper.frames_per_model.size() > 1) {
    out << "models: " << mapper.frames_per_model.size()
        << " (models/1/, ...: " << mapper.num_frames_in_other_models
        << " frames the images join to none of model/'s), " << mapper.num_models_merged
        << " merged\n";
  }
  if (mapper.images_only) out << "images only: no VIO pose placed a frame\n";
  if (!camera_refined.empty()) out << "camera (guessed, refined): " << camera_refined << "\n";
  if (!mapper.imu_alignment_message.empty()) out << "IMU: " << mapper.imu_alignment_message << "\n";
  out << "every image: " << all_frames.num_images << ": " << all_frames.num_from_model
      << " from the model, " << all_frames.num_between << " between model frames, "
      << all_frames.num_beyond << " beyond its VIO segment's model frames, "
      << all_frames.num_unposed() << " unposed\n";
  if (texture_probe.probed) {
    // The probe's figures: summary.json and run.log.
    out << "texture: "
        << (texture_probe.textured ? "rich: fewer frames with more features"
                                   : "not rich: the rate and the feature count as set")
        << "\n";
  }
  if (vio_gaps.num_gaps > 0) out << "VIO gaps: " << vio_gaps.ToString() << "\n";
  out << "VIO: " << num_vio_segments << " segment(s), " << mapper.num_vio_segments_joined
      << " joined; re-posed by the images " << mapper.num_reposed
      << ", registered without a VIO pose " << mapper.num_registered_without_vio << "; jumps found "
      << mapper.num_vio_breaks << ", refused " << mapper.num_vio_jumps_refused << "\n";
  // The metric scale's line is among the decisions (its details: summary.json, run.log).
  out << "pairs: " << FormatVerificationHeadline(verification) << "\n";
  out << "points: " << num_points << ", observations " << num_observations << ", mean track length "
      << mean_track_length << ", mean reprojection error " << mean_reprojection_error_px << " px\n";
  if (evaluation) {
    out << "ATE (Sim(3), " << evaluation->num_poses << " poses): RMSE " << evaluation->ate_rmse_m
        << " m, median " << evaluation->ate_median_m << " m";
    if (evaluation->has_vio) {
      out << "; input VIO RMSE " << evaluation->vio_ate_rmse_m << " m, median "
          << evaluation->vio_ate_median_m << " m";
    }
    out << "\n";
    out << "metric: " << FormatMetricAccuracy(evaluation->metric) << "\n";
    if (evaluation->has_vio) {
      out << "input VIO: " << FormatMetricAccuracy(evaluation->vio_metric) << "\n";
    }
    if (evaluation->all_frames_metric) {
      out << "every image: " << FormatMetricAccuracy(*evaluation->all_frames_metric) << " ("
          << evaluation->all_frames_metric->num_poses << " poses)\n";
    }
    out << std::fixed << std::setprecision(3);
  } else {
    out << "ATE: no ground truth\n";
  }
  if (gyro_check) {
    out << std::setprecision(3) << "rotations against the gyro (" << gyro_check->num_intervals
        << " x 1 s, a consistency check): RMSE " << gyro_check->rmse_deg << " deg, median "
        << gyro_check->median_deg << ", max " << gyro_check->max_deg << " (" << std::setprecision(2)
        << gyro_check->worst_from_s << " to " << gyro_check->worst_to_s << " s)\n";
  } else if (!gyro_check_message.empty()) {
    out << "rotations against the gyro: " << gyro_check_message << "\n";
  }
  out << "images: " << images.decodes << " decoded, " << images.reuses << " from the frame cache, "
      << images.not_kept << " not kept for lack of room (cache peak " << std::setprecision(1)
      << static_cast<double>(images.peak_bytes) / (1 << 20) << " of "
      << static_cast<double>(frame_cache_max_bytes) / (1 << 20) << " MiB)\n";
  double cpu_seconds = 0.0;
  for (const PipelineStageTime& stage : stages) cpu_seconds += stage.cpu_seconds;
  out << std::setprecision(1) << "time: " << total_seconds << " s, CPU " << cpu_seconds
      << " s, peak memory " << peak_memory_mb << " MB; the longest stages:";
  std::vector<PipelineStageTime> longest = stages;
  std::sort(
      longest.begin(), longest.end(),
      [](const PipelineStageTime& a, const PipelineStageTime& b) { return a.seconds > b.seconds; });
  for (size_t i = 0; i < longest.size() && i < 3; ++i) {
    out << (i > 0 ? "," : "") << " " << longest[i].name << " " << longest[i].seconds << " s";
  }
  out << "\n";
  if (stream.streamed) {
    out << "stream: VIO done after " << stream.vio_seconds << " s, verification after "
        << stream.verification_seconds << " s (" << stream.verification_busy_seconds
        << " s busy), mapper after " << stream.mapper_seconds << " s\n";
    out << "stream: the model " << stream.seconds_after_last_frame
        << " s after the last frame's features";
    if (stream.followed) {
      out << "; the recording ended after " << stream.recording_end_seconds
          << " s, the model was ready " << stream.seconds_after_recording_end << " s later";
    }
    out << "\n";
  }
  out << "output: " << output_folder.string()
      << " (model/, points.ply, trajectory_*.tum, summary.json, run.log)";
  const std::vector<std::string> warnings = RunWarnings(*this);
  out << "\ndecisions (summary.json: warnings):" << (warnings.empty() ? " none" : "");
  for (const std::string& line : warnings) out << "\n  " << line;
  return WrapLines(out.str());
}

namespace {

// The frames, the models and every image of the recording.
void AddFramesJson(const PipelineSummary& s, ordered_json* out) {
  ordered_json& json = *out;
  json["frames"] = {{"in", s.num_frames_in},
                    {"selected", s.num_frames_selected},
                    {"without_vio_pose", s.num_frames_without_vio_pose},
                    {"registered", s.num_frames_registered},
                    {"vio_only", s.num_frames_vio_only},
                    {"unposed", s.num_frames_unposed},
                    {"reposed_from_images", s.mapper.num_reposed},
                    {"reposed_after_adjustment", s.mapper.num_reposed_after_adjustment},
                    {"registered_without_vio", s.mapper.num_registered_without_vio},
                    {"in_other_models", s.mapper.num_frames_in_other_models}};
  // The main model (model/) first, then the separate ones (models/1/, ...).
  json["models"] = {{"frames", s.mapper.frames_per_model},
                    {"merged", s.mapper.num_models_merged},
                    {"images_only", s.mapper.images_only},
                    {"imu_alignment", s.mapper.imu_alignment_message},
                    {"camera_refined", s.camera_refined}};
  json["all_frames"] = {{"images", s.all_frames.num_images},
                        {"from_model", s.all_frames.num_from_model},
                        {"between_model_frames", s.all_frames.num_between},
                        {"beyond_model_frames", s.all_frames.num_beyond},
                        {"unposed", s.all_frames.num_unposed()},
                        {"without_vio_pose", s.all_frames.num_without_vio_pose},
                        {"without_model_frame", s.all_frames.num_without_model_frame},
                        {"file", "trajectory_body_all_frames.tum"}};
}

// The metric scale, the texture probe and the rolling shutter.
void AddScaleJson(const PipelineSummary& s, ordered_json* out) {
  ordered_json& json = *out;
  json["imu_scale"] = {{"estimated", s.metric_scale.estimated},
                       {"usable", s.metric_scale.imu.usable},
                       {"imu_scale", s.metric_scale.imu.scale},
                       {"imu_scale_sigma", s.metric_scale.imu.scale_sigma},
                       {"spaced_scale", s.metric_scale.imu.spaced_scale},
                       {"spaced_scale_sigma", s.metric_scale.imu.spaced_scale_sigma},
                       {"spacing_disagrees", s.metric_scale.imu.spacing_disagrees},
                       {"spaced_used", s.metric_scale.imu.spaced_used},
                       {"applied_scale", s.metric_scale.applied_scale},
                       {"applied_scale_sigma", s.metric_scale.applied_scale_sigma},
                       {"vio_scale_refuted", s.metric_scale.vio_scale_refuted},
                       {"factor_scale", s.metric_scale.factor_scale},
                       {"factor_scale_used", s.metric_scale.factor_scale_used},
                       {"levelling_deg", s.metric_scale.levelling_deg},
                       {"message", s.metric_scale.message}};
  json["texture_probe"] = {{"probed", s.texture_probe.probed},
                           {"planned", s.texture_probe.num_planned},
                           {"frames", s.texture_probe.frames},
                           {"num_keypoints", s.texture_probe.num_keypoints},
                           {"deciding_count", s.texture_probe.deciding_count},
                           {"textured", s.texture_probe.textured},
                           {"seconds", s.texture_probe.seconds},
                           {"message", s.texture_probe_message},
                           {"frame_rate_hz", s.frame_rate_hz},
                           {"max_num_features", s.max_num_features}};
  json["rolling_shutter"] = {{"readout_s", s.rolling_shutter_readout_s},
                             {"source", s.rolling_shutter_source},
                             {"motion_message", s.mapper.rolling_shutter_message}};
}

// The VIO's segments and gaps, its own summary, and the frames without a
// pose or placed by the VIO alone.
void AddVioJson(const PipelineSummary& s, ordered_json* out) {
  ordered_json& json = *out;
  json["vio"] = {{"segments", s.num_vio_segments},
                 {"segments_joined", s.mapper.num_vio_segments_joined},
                 {"segment_rule", s.vio_segment_rule},
                 {"gaps",
                  {{"candidates", s.vio_gaps.num_gaps},
                   {"confirmed", s.vio_gaps.num_confirmed},
                   {"contradicted", s.vio_gaps.num_jumps},
                   {"without_pairs", s.vio_gaps.num_unseen},
                   {"without_pairs_kept", s.vio_gaps.num_unseen_kept},
                   {"pairs_dropped", s.vio_gaps.num_pairs_dropped}}},
                 {"jumps_found", s.mapper.num_vio_breaks},
                 {"jumps_refused", s.mapper.num_vio_jumps_refused}};
  if (s.own_vio_summary) {
    // viosfm's own VIO: its frames by status; IMU-only and lost frames are
    // posed by the IMU alone.
    const VioSummary& own = *s.own_vio_summary;
    const auto count = [&](VioStatus status) {
      return own.status_counts[static_cast<int>(status)];
    };
    json["vio"]["own"] = {{"frames", own.num_frames},
                          {"frames_tracking", count(VioStatus::kTracking)},
                          {"frames_initializing", count(VioStatus::kInitializing)},
                          {"frames_imu_only", count(VioStatus::kImuOnly)},
                          {"frames_lost", count(VioStatus::kLost)},
                          {"imu_only_stretches", own.num_imu_only_stretches},
                          {"longest_imu_only_s", own.longest_imu_only_s},
                          {"resets", own.num_resets},
                          {"imu_breaks", own.imu_breaks.size()},
                          {"frames_without_pose", own.num_frames_without_pose}};
  }
  ordered_json unposed = ordered_json::array();
  for (const MapperFrameStatus& frame : s.mapper.frames) {
    if (!frame.reason.empty()) {
      unposed.push_back({{"image_id", frame.image_id}, {"reason", frame.reason}});
    }
  }
  json["unposed_frames"] = unposed;
  ordered_json vio_only = ordered_json::array();
  for (const MapperFrameStatus& frame : s.mapper.frames) {
    if (frame.source != FramePoseSource::kNone && !frame.supported) {
      vio_only.push_back({{"image_id", frame.image_id},
                          {"supporting_observations", frame.num_supporting_observations}});
    }
  }
  json["vio_only_frames"] = vio_only;
}

// The pairs, the points, the tracks, the priors and the adjustments.
void AddModelJson(const PipelineSummary& s, ordered_json* out) {
  ordered_json& json = *out;
  json["pairs"] = {{"candidates", s.verification.num_pairs},
                   {"accepted", s.verification.num_accepted},
                   {"accepted_corrected", s.verification.num_accepted_corrected},
                   {"vio_rejected", s.verification.num_vio_rejected},
                   {"ransac_rejected", s.verification.num_ransac_rejected},
                   {"no_matches", s.verification.num_no_matches}};
  json["points"] = s.num_points;
  json["observations"] = s.num_observations;
  json["mean_track_length"] = s.mean_track_length;
  json["mean_reprojection_error_px"] = s.mean_reprojection_error_px;
  json["tracks"] = {{"tracks", s.mapper.tracks.num_tracks},
                    {"observations", s.mapper.tracks.num_observations},
                    {"inconsistent_components", s.mapper.tracks.num_inconsistent_components},
                    {"refused_matches", s.mapper.tracks.num_refused_matches},
                    {"points_joined", s.mapper.num_points_merged},
                    {"observations_split_off", s.mapper.num_observations_split_off}};
  json["relative_pose_priors"] = {{"consecutive", s.mapper.num_consecutive_priors},
                                  {"bridging", s.mapper.num_bridging_priors},
                                  {"gyro", s.mapper.num_gyro_priors},
                                  {"gyro_message", s.mapper.gyro_message}};
  json["imu_factors"] = {{"factors", s.mapper.num_inertial_factors},
                         {"scale", s.mapper.inertial_scale},
                         {"message", s.mapper.inertial_message}};
  json["final_adjustment"] = {{"refinements", s.mapper.num_final_ba_refinements},
                              {"last_change", s.mapper.final_ba_last_change},
                              {"observations", s.mapper.final_ba.num_observations},
                              {"iterations", s.mapper.final_ba.num_iterations},
                              {"seconds", s.mapper.final_ba.time_s}};
}

// The mapper's batches, the stages' times and a streamed run's threads.
void AddTimesJson(const PipelineSummary& s, ordered_json* out) {
  ordered_json& json = *out;
  ordered_json batches = ordered_json::array();
  for (const MapperBatchStatistics& batch : s.mapper.batches) {
    batches.push_back({{"index", batch.batch_index},
                       {"images", batch.num_images},
                       {"registered_total", batch.num_registered_total},
                       {"points_total", batch.num_points_total},
                       {"mean_reprojection_error_px", batch.mean_reprojection_error_px},
                       {"seconds_registration", batch.seconds_registration},
                       {"seconds_triangulation", batch.seconds_triangulation},
                       {"seconds_ba", batch.seconds_ba},
                       {"seconds_filtering", batch.seconds_filtering},
                       {"seconds_total", batch.seconds_total},
                       {"ba_observations", batch.num_ba_observations},
                       {"ba_iterations", batch.num_ba_iterations},
                       {"ba_solver", BaLinearSolverName(batch.ba_linear_solver)}});
  }
  json["batches"] = batches;
  ordered_json stages = ordered_json::array();
  for (const PipelineStageTime& stage : s.stages) {
    stages.push_back(
        {{"name", stage.name}, {"seconds", stage.seconds}, {"cpu_seconds", stage.cpu_seconds}});
  }
  json["stages"] = stages;
  if (s.stream.streamed) {
    json["stream"] = {{"vio_seconds", s.stream.vio_seconds},
                      {"verification_seconds", s.stream.verification_seconds},
                      {"verification_busy_seconds", s.stream.verification_busy_seconds},
                      {"mapper_seconds", s.stream.mapper_seconds},
                      {"features_beside_vio", s.stream.num_features_beside},
                      {"seconds_after_last_frame", s.stream.seconds_after_last_frame},
                      {"vocabulary_frames", s.stream.num_vocabulary_frames}};
    if (s.stream.followed) {
      json["stream"]["recording_end_seconds"] = s.stream.recording_end_seconds;
      json["stream"]["seconds_after_recording_end"] = s.stream.seconds_after_recording_end;
    }
  }
}

}  // namespace

std::string PipelineSummaryToJson(const PipelineSummary& s) {
  ordered_json json;
  json["viosfm_version"] = ViosfmVersion();
  json["dataset"] = s.dataset;
  json["started_utc"] = s.started_utc;
  AddFramesJson(s, &json);
  AddScaleJson(s, &json);
  AddVioJson(s, &json);
  AddModelJson(s, &json);
  AddTimesJson(s, &json);
  json["images"] = {{"decoded", s.images.decodes},
                    {"reused", s.images.reuses},
                    {"not_kept", s.images.not_kept},
                    {"cache_peak_bytes", s.images.peak_bytes},
                    {"cache_max_bytes", s.frame_cache_max_bytes}};
  json["total_seconds"] = s.total_seconds;
  json["peak_memory_mb"] = s.peak_memory_mb;
  if (s.evaluation) json["eval"] = StatsJson(*s.evaluation);
  if (s.gyro_check) {
    const PipelineGyroCheck& g = *s.gyro_check;
    json["gyro_check"] = {{"intervals", g.num_intervals},      {"rmse_deg", g.rmse_deg},
                          {"median_deg", g.median_deg},        {"max_deg", g.max_deg},
                          {"worst_from_s", g.worst_from_s},    {"worst_to_s", g.worst_to_s},
                          {"time_offset_ns", g.time_offset_ns}};
  } else {
    json["gyro_check"] = {{"message", s.gyro_check_message}};
  }
  json["warnings"] = RunWarnings(s);
  json["options_file"] = "options.json";
  json["fingerprint"] = s.fingerprint;
  return json.dump(2);
}

}  // namespace viosfm

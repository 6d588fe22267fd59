#include "viosfm/eval/report.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

void AppendStatisticsRow(std::ostringstream& out, const std::string& name,
                         const ErrorStatistics& stats) {
  char line[256];
  std::snprintf(line, sizeof(line), "  %-26s %7zu %12.6g %12.6g %12.6g %12.6g %12.6g %12.6g\n",
                name.c_str(), stats.count, stats.rmse, stats.mean, stats.median, stats.std,
                stats.min, stats.max);
  out << line;
}

nlohmann::json StatisticsJson(const ErrorStatistics& stats) {
  return {{"count", stats.count},   {"rmse", stats.rmse}, {"mean", stats.mean},
          {"median", stats.median}, {"std", stats.std},   {"min", stats.min},
          {"max", stats.max},       {"sse", stats.sse}};
}

nlohmann::json RelativeJson(const RelativePoseErrors& rpe) {
  return {{"delta", rpe.delta},
          {"unit", rpe.unit},
          {"all_pairs", rpe.all_pairs},
          {"num_pairs", rpe.pair_indices.size()},
          {"translation_m", StatisticsJson(rpe.translation_m)},
          {"rotation_deg", StatisticsJson(rpe.rotation_deg)}};
}

nlohmann::json PoseJson(const std::optional<Rigid3d>& pose) {
  if (!pose) return nullptr;
  const Eigen::Quaterniond& q = pose->rotation;
  const Eigen::Vector3d& t = pose->translation;
  return {{"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}}, {"translation", {t.x(), t.y(), t.z()}}};
}

}  // namespace

std::string FormatEvaluationReport(const EvaluationResult& result, const EvaluationOptions& options,
                                   const EvaluationInputs& inputs) {
  std::ostringstream out;
  out << "estimate:    " << inputs.est_path << " (" << inputs.est_format << ", "
      << result.num_est_poses << " poses" << (options.est_body_from_cam ? ", camera -> body" : "")
      << ")\n";
  out << "reference:   " << inputs.ref_path << " (" << inputs.ref_format << ", "
      << result.num_ref_poses << " poses" << (options.ref_body_from_cam ? ", camera -> body" : "")
      << ")\n";
  out << "association: " << AssociationMethodName(result.association);
  if (result.association != AssociationMethod::kIndex) {
    out << " (max dt " << FormatNsAsSeconds(options.max_dt_ns) << " s, offset "
        << FormatNsAsSeconds(options.offset_ns) << " s)";
  }
  out << ", " << result.pairs.size() << " pairs\n";
  const Sim3d& s = result.ref_from_est;
  out << "alignment:   " << AlignmentModeName(result.alignment) << " on "
      << result.num_alignment_pairs << " pairs, scale " << FormatDouble("%.9g", s.scale)
      << ", t = [" << FormatDouble("%.6g", s.translation.x()) << ", "
      << FormatDouble("%.6g", s.translation.y()) << ", " << FormatDouble("%.6g", s.translation.z())
      << "], q_wxyz = [" << FormatDouble("%.6g", s.rotation.w()) << ", "
      << FormatDouble("%.6g", s.rotation.x()) << ", " << FormatDouble("%.6g", s.rotation.y())
      << ", " << FormatDouble("%.6g", s.rotation.z()) << "]\n\n";
  char header[256];
  std::snprintf(header, sizeof(header), "  %-26s %7s %12s %12s %12s %12s %12s %12s\n", "metric",
                "count", "rmse", "mean", "median", "std", "min", "max");
  out << header;
  AppendStatisticsRow(out, "ATE translation (m)", result.ate_translation_m);
  AppendStatisticsRow(out, "ATE rotation (deg)", result.ate_rotation_deg);
  for (const auto* rpe : {&result.rpe_frames, &result.rpe_distance}) {
    if (!rpe->has_value()) continue;
    const std::string delta = FormatDouble("%g", (*rpe)->delta) + " " + (*rpe)->unit;
    AppendStatisticsRow(out, "RPE " + delta + " trans (m)", (*rpe)->translation_m);
    AppendStatisticsRow(out, "RPE " + delta + " rot (deg)", (*rpe)->rotation_deg);
  }
  return out.str();
}

std::string EvaluationToJson(const EvaluationResult& result, const EvaluationOptions& options,
                             const EvaluationInputs& inputs) {
  const Sim3d& s = result.ref_from_est;
  nlohmann::json json = {
      {"inputs",
       {{"est_path", inputs.est_path},
        {"est_format", inputs.est_format},
        {"ref_path", inputs.ref_path},
        {"ref_format", inputs.ref_format}}},
      {"options",
       {{"association", AssociationMethodName(options.association)},
        {"max_dt_ns", options.max_dt_ns},
        {"offset_ns", options.offset_ns},
        {"alignment", AlignmentModeName(options.alignment)},
        {"align_first", options.align_first},
        {"rpe_delta_frames", options.rpe_delta_frames},
        {"rpe_delta_m", options.rpe_delta_m},
        {"rpe_delta_m_tolerance", options.rpe_delta_m_tolerance},
        {"rpe_all_pairs", options.rpe_all_pairs},
        {"est_body_from_cam", PoseJson(options.est_body_from_cam)},
        {"ref_body_from_cam", PoseJson(options.ref_body_from_cam)}}},
      {"num_est_poses", result.num_est_poses},
      {"num_ref_poses", result.num_ref_poses},
      {"association", AssociationMethodName(result.association)},
      {"num_pairs", result.pairs.size()},
      {"alignment",
       {{"mode", AlignmentModeName(result.alignment)},
        {"num_pairs", result.num_alignment_pairs},
        {"scale", s.scale},
        {"rotation_wxyz", {s.rotation.w(), s.rotation.x(), s.rotation.y(), s.rotation.z()}},
        {"translation", {s.translation.x(), s.translation.y(), s.translation.z()}}}},
      {"ate",
       {{"translation_m", StatisticsJson(result.ate_translation_m)},
        {"rotation_deg", StatisticsJson(result.ate_rotation_deg)}}},
  };
  if (result.rpe_frames) json["rpe_frames"] = RelativeJson(*result.rpe_frames);
  if (result.rpe_distance) json["rpe_distance"] = RelativeJson(*result.rpe_distance);
  return json.dump(2) + "\n";
}

void WriteEvaluationJson(const std::filesystem::path& path, const EvaluationResult& result,
                         const EvaluationOptions& options, const EvaluationInputs& inputs) {
  const std::string text = EvaluationToJson(result, options, inputs);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text; });
}

std::string GyroCheckToJson(const GyroCheckResult& result, const GyroCheckOptions& options) {
  nlohmann::json intervals = nlohmann::json::array();
  for (const GyroCheckInterval& interval : result.intervals) {
    intervals.push_back({{"from_ns", interval.from_ns},
                         {"to_ns", interval.to_ns},
                         {"gyro_angle_deg", interval.gyro_angle_deg},
                         {"error_deg", interval.error_deg}});
  }
  const nlohmann::json json = {
      {"options",
       {{"interval_s", options.interval_s},
        {"max_interval_factor", options.max_interval_factor},
        {"fit_bias", options.fit_bias}}},
      {"num_frames", result.num_frames},
      {"num_intervals", result.intervals.size()},
      {"num_without_imu", result.num_without_imu},
      {"num_gaps", result.num_gaps},
      {"time_offset_ns", result.time_offset_ns},
      {"bias_fitted", result.bias_fitted},
      {"num_bias_intervals", result.num_bias_intervals},
      {"gyro_bias_rad_s", {result.gyro_bias.x(), result.gyro_bias.y(), result.gyro_bias.z()}},
      {"error_deg", StatisticsJson(result.error_deg)},
      {"intervals", intervals}};
  return json.dump(2) + "\n";
}

}  // namespace viosfm

#include "viosfm/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "viosfm/io/colmap_model.h"
#include "viosfm/io/dataset.h"
#include "viosfm/io/ply.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/report/json_file.h"
#include "viosfm/report/run_plots.h"
#include "viosfm/report/svg_plot.h"
#include "viosfm/report/viewer_3d.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"

namespace viosfm {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

// Default VIO outlier-ratio threshold (the paper's 0.5), used when the
// verification options do not state it.
constexpr double kDefaultOutlierRatioThreshold = 0.5;
constexpr int kHistogramBins = 20;

const char* kStyle = R"(
body { font-family: sans-serif; margin: 24px auto; padding: 0 16px; max-width: 1200px; color: #222; }
h1 { font-size: 24px; margin-bottom: 4px; }
h2 { font-size: 19px; border-bottom: 1px solid #ccc; padding-bottom: 3px; margin-top: 32px; }
.meta { color: #666; font-size: 13px; }
table { border-collapse: collapse; margin: 8px 0; font-size: 14px; }
th, td { border: 1px solid #ddd; padding: 4px 10px; }
th { background: #f2f2f2; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.figures { display: flex; flex-wrap: wrap; gap: 12px; }
.note { color: #8a5a00; background: #fff6e0; padding: 6px 10px; border-left: 3px solid #e0a000; }
.options td { font-family: monospace; font-size: 12px; }
#decisions { background: #fff6e0; border-left: 3px solid #e0a000; margin: 12px 0;
  padding: 6px 10px 6px 28px; font-size: 14px; }
#decisions li { margin: 2px 0; }
)";

std::string Escape(const std::string& text) {
  return XmlEscape(text);
}

std::string Integer(std::optional<double> value) {
  if (!value || !std::isfinite(*value)) return "n/a";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.0f", *value);
  return buffer;
}

Json ReadJson(const fs::path& path) {
  return ReadJsonFile(path);
}

std::optional<Json> ReadOptionalJson(const fs::path& path) {
  if (!fs::is_regular_file(path)) return std::nullopt;
  return ReadJson(path);
}

// The value at a '/'-separated key path, if it is there and not null.
const Json* Find(const Json& json, const std::string& key_path) {
  const Json* node = &json;
  for (std::string_view key : Split(key_path, "/")) {
    if (!node->is_object()) return nullptr;
    const auto it = node->find(std::string(key));
    if (it == node->end()) return nullptr;
    node = &*it;
  }
  return node->is_null() ? nullptr : node;
}

std::optional<double> Number(const Json& json, const std::string& key_path) {
  const Json* node = Find(json, key_path);
  if (node == nullptr || !node->is_number()) return std::nullopt;
  return node->get<double>();
}

std::string Text(const Json& json, const std::string& key_path) {
  const Json* node = Find(json, key_path);
  if (node == nullptr) return "";
  return node->is_string() ? node->get<std::string>() : node->dump();
}

// ATE statistics of one trajectory, from its eval JSON or the summary.
struct AteNumbers {
  std::optional<double> rmse, mean, median, max;
  std::optional<double> count;
  std::string alignment;
  std::string source;  // file the numbers came from
  bool Any() const { return rmse || median || mean || max; }
};

AteNumbers AteFromEvalJson(const Json& eval, const std::string& source) {
  AteNumbers ate;
  ate.rmse = Number(eval, "ate/translation_m/rmse");
  ate.mean = Number(eval, "ate/translation_m/mean");
  ate.median = Number(eval, "ate/translation_m/median");
  ate.max = Number(eval, "ate/translation_m/max");
  ate.count = Number(eval, "ate/translation_m/count");
  ate.alignment = Text(eval, "alignment/mode");
  ate.source = source;
  return ate;
}

struct RunData {
  fs::path run_dir;
  Json summary;
  std::optional<Json> options;
  std::optional<Json> eval;
  std::optional<Json> eval_vio;
  std::optional<Json> verification;
  Trajectory estimate, vio, ground_truth;
  bool has_estimate = false, has_vio = false, has_ground_truth = false;
  // VIO outlier ratios of the pairs whose check ran.
  std::vector<double> outlier_ratios;
  bool has_pairs = false;
  std::string pairs_source;
  AteNumbers ate, vio_ate;
};

// Reads the "vio_outlier_ratio" column of pairs.csv ("nan": the check did not run).
std::vector<double> ReadOutlierRatiosCsv(const fs::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::string line;
  int64_t line_number = 0;
  int column = -1;
  std::vector<double> ratios;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (Trim(line).empty()) continue;
    const std::vector<std::string_view> fields = Split(line, ",");
    if (column < 0) {
      for (size_t i = 0; i < fields.size(); ++i) {
        if (Trim(fields[i]) == "vio_outlier_ratio") column = static_cast<int>(i);
      }
      if (column < 0) {
        throw InputError(path.string(), line_number,
                         "expected a header line with a 'vio_outlier_ratio' column");
      }
      continue;
    }
    if (static_cast<size_t>(column) >= fields.size()) {
      throw InputError(path.string(), line_number,
                       "expected at least " + std::to_string(column + 1) + " fields");
    }
    const std::string_view field = Trim(fields[column]);
    if (ToLower(field) == "nan" || field.empty()) continue;
    const std::optional<double> ratio = ParseDouble(field);
    if (!ratio) {
      throw InputError(
          path.string(), line_number,
          "expected a number or 'nan' as vio_outlier_ratio, got '" + std::string(field) + "'");
    }
    ratios.push_back(*ratio);
  }
  return ratios;
}

RunData LoadRun(const fs::path& run_dir) {
  RunData run;
  run.run_dir = run_dir;
  const fs::path summary_path = run_dir / "summary.json";
  if (!fs::is_regular_file(summary_path)) {
    throw InputError(summary_path.string(), 0,
                     "missing: expected the summary.json of a `viosfm run` output folder");
  }
  run.summary = ReadJson(summary_path);
  if (!run.summary.is_object()) {
    throw InputError(summary_path.string(), 1, "expected a JSON object");
  }
  run.options = ReadOptionalJson(run_dir / "options.json");
  run.eval = ReadOptionalJson(run_dir / "eval.json");
  run.eval_vio = ReadOptionalJson(run_dir / "eval_vio.json");
  run.verification = ReadOptionalJson(run_dir / "verification" / "verification.json");

  const auto read_trajectory = [&run_dir](const std::string& name, Trajectory* trajectory) {
    const fs::path path = run_dir / name;
    if (!fs::is_regular_file(path)) return false;
    *trajectory = ReadTumTrajectory(path);
    return !trajectory->empty();
  };
  run.has_estimate = read_trajectory("trajectory_body.tum", &run.estimate);
  run.has_vio = read_trajectory("vio_body.tum", &run.vio);
  run.has_ground_truth = read_trajectory("groundtruth_body.tum", &run.ground_truth);

  const fs::path pairs_csv = run_dir / "verification" / "pairs.csv";
  if (fs::is_regular_file(pairs_csv)) {
    run.outlier_ratios = ReadOutlierRatiosCsv(pairs_csv);
    run.has_pairs = true;
    run.pairs_source = "verification/pairs.csv";
  } else if (run.verification) {
    if (const Json* pairs = Find(*run.verification, "pairs"); pairs && pairs->is_array()) {
      for (const Json& pair : *pairs) {
        if (const std::optional<double> ratio = Number(pair, "vio_outlier_ratio")) {
          run.outlier_ratios.push_back(*ratio);
        }
      }
      run.has_pairs = true;
      run.pairs_source = "verification/verification.json";
    }
  }

  // ATE: the eval files hold every statistic; the summary the main ones.
  if (run.eval) {
    run.ate = AteFromEvalJson(*run.eval, "eval.json");
  } else if (Find(run.summary, "eval")) {
    run.ate.rmse = Number(run.summary, "eval/ate_rmse_m");
    run.ate.mean = Number(run.summary, "eval/ate_mean_m");
    run.ate.median = Number(run.summary, "eval/ate_median_m");
    run.ate.max = Number(run.summary, "eval/ate_max_m");
    run.ate.count = Number(run.summary, "eval/num_poses");
    run.ate.alignment = Text(run.summary, "eval/alignment");
    run.ate.source = "summary.json";
  }
  if (run.eval_vio) {
    run.vio_ate = AteFromEvalJson(*run.eval_vio, "eval_vio.json");
  } else if (Find(run.summary, "eval")) {
    run.vio_ate.rmse = Number(run.summary, "eval/vio_ate_rmse_m");
    run.vio_ate.median = Number(run.summary, "eval/vio_ate_median_m");
    run.vio_ate.alignment = Text(run.summary, "eval/alignment");
    run.vio_ate.source = "summary.json";
  }
  return run;
}

class Page {
 public:
  void Heading(const std::string& text, const std::string& id) {
    out_ << "<h2 id=\"" << id << "\">" << Escape(text) << "</h2>\n";
  }
  void Note(const std::string& text) { out_ << "<p class=\"note\">" << Escape(text) << "</p>\n"; }
  void Paragraph(const std::string& text) { out_ << "<p>" << Escape(text) << "</p>\n"; }
  // A two-column table of (name, value) rows; values right-aligned.
  void KeyValueTable(const std::string& id,
                     const std::vector<std::pair<std::string, std::string>>& rows,
                     const std::string& css_class = "") {
    out_ << "<table id=\"" << id << '"';
    if (!css_class.empty()) out_ << " class=\"" << css_class << '"';
    out_ << ">\n";
    for (const auto& [name, value] : rows) {
      out_ << "<tr><th>" << Escape(name) << "</th><td class=\"num\">" << Escape(value)
           << "</td></tr>\n";
    }
    out_ << "</table>\n";
  }
  void Table(const std::string& id, const std::vector<std::string>& header,
             const std::vector<std::vector<std::string>>& rows) {
    out_ << "<table id=\"" << id << "\">\n<tr>";
    for (const std::string& h : header) out_ << "<th>" << Escape(h) << "</th>";
    out_ << "</tr>\n";
    for (const auto& row : rows) {
      out_ << "<tr>";
      for (size_t i = 0; i < row.size(); ++i) {
        out_ << (i == 0 ? "<td>" : "<td class=\"num\">") << Escape(row[i]) << "</td>";
      }
      out_ << "</tr>\n";
    }
    out_ << "</table>\n";
  }
  void Figures(const std::vector<std::string>& svgs) {
    out_ << "<div class=\"figures\">\n";
    for (const std::string& svg : svgs) out_ << "<div class=\"figure\">" << svg << "</div>\n";
    out_ << "</div>\n";
  }
  std::ostringstream& out() { return out_; }

 private:
  std::ostringstream out_;
};

// The run's decisions a user should know (summary.json's `warnings`: time
// offset, IMU noise, scale source and uncertainty, frames without a pose,
// VIO segments, IMU-only stretches), one line each, at the top.
void DecisionsList(const RunData& run, Page* page) {
  const Json* warnings = Find(run.summary, "warnings");
  if (warnings == nullptr || !warnings->is_array()) return;
  std::ostringstream& out = page->out();
  out << "<ul id=\"decisions\" title=\"The run's decisions (summary.json: warnings)\">\n";
  for (const Json& line : *warnings) {
    if (line.is_string()) out << "<li>" << Escape(line.get<std::string>()) << "</li>\n";
  }
  out << "</ul>\n";
}

void SummarySection(const RunData& run, Page* page) {
  const Json& s = run.summary;
  page->Heading("Summary", "summary");
  const std::optional<double> frames_in = Number(s, "frames/in");
  const std::optional<double> registered = Number(s, "frames/registered");
  std::string registered_text = Integer(registered);
  if (frames_in && registered && *frames_in > 0) {
    registered_text += " (" + FormatFixedOrNa(100.0 * *registered / *frames_in, 1) + " %)";
  }
  std::vector<std::pair<std::string, std::string>> rows = {
      {"frames in", Integer(frames_in)},
      {"frames selected", Integer(Number(s, "frames/selected"))},
      {"frames registered (pose supported by the images)", registered_text},
      {"frames placed by the VIO only", Integer(Number(s, "frames/vio_only"))},
      {"frames without a pose", Integer(Number(s, "frames/unposed"))},
      {"selected frames without a VIO pose", Integer(Number(s, "frames/without_vio_pose"))},
      {"frames re-posed from the images (the VIO disagreed)",
       Integer(Number(s, "frames/reposed_from_images"))},
      {"VIO segments (joined)",
       Integer(Number(s, "vio/segments")) + " (" + Integer(Number(s, "vio/segments_joined")) + ")"},
      {"3D points", Integer(Number(s, "points"))},
      {"observations", Integer(Number(s, "observations"))},
      {"mean track length", FormatFixedOrNa(Number(s, "mean_track_length"), 2)},
      {"mean reprojection error (px)", FormatFixedOrNa(Number(s, "mean_reprojection_error_px"), 3)},
  };
  if (Text(s, "texture_probe/probed") == "true") {
    rows.push_back({"frame rate and features, from the texture", Text(s, "texture_probe/message")});
  }
  if (Find(s, "all_frames")) {
    rows.push_back(
        {"every image of the recording (trajectory_body_all_frames.tum)",
         Integer(Number(s, "all_frames/images")) +
             " images: " + Integer(Number(s, "all_frames/from_model")) + " from the model, " +
             Integer(Number(s, "all_frames/between_model_frames")) + " between model frames, " +
             Integer(Number(s, "all_frames/beyond_model_frames")) + " beyond them, " +
             Integer(Number(s, "all_frames/unposed")) + " without a pose"});
  }
  if (run.ate.Any()) {
    rows.push_back({"ATE RMSE, viosfm (m)", FormatFixedOrNa(run.ate.rmse, 4)});
    rows.push_back({"ATE median, viosfm (m)", FormatFixedOrNa(run.ate.median, 4)});
  } else {
    rows.push_back({"ATE, viosfm", "no ground truth"});
  }
  if (run.vio_ate.Any()) {
    rows.push_back({"ATE RMSE, input VIO (m)", FormatFixedOrNa(run.vio_ate.rmse, 4)});
    rows.push_back({"ATE median, input VIO (m)", FormatFixedOrNa(run.vio_ate.median, 4)});
  } else {
    rows.push_back({"ATE, input VIO", "no ground truth"});
  }
  if (Find(s, "gyro_check/rmse_deg")) {
    rows.push_back({"rotations against the gyro over 1 s (deg; the model uses the gyro)",
                    "RMSE " + FormatFixedOrNa(Number(s, "gyro_check/rmse_deg"), 3) + ", max " +
                        FormatFixedOrNa(Number(s, "gyro_check/max_deg"), 3) + " (" +
                        FormatFixedOrNa(Number(s, "gyro_check/worst_from_s"), 2) + " to " +
                        FormatFixedOrNa(Number(s, "gyro_check/worst_to_s"), 2) + " s), " +
                        Integer(Number(s, "gyro_check/intervals")) + " intervals"});
  } else if (Find(s, "gyro_check/message")) {
    rows.push_back({"rotations against the gyro", Text(s, "gyro_check/message")});
  }
  rows.push_back({"total time (s)", FormatFixedOrNa(Number(s, "total_seconds"), 2)});
  rows.push_back({"peak memory (MB)", FormatFixedOrNa(Number(s, "peak_memory_mb"), 1)});
  page->KeyValueTable("summary-table", rows);
  if (const Json* unposed = Find(s, "unposed_frames");
      unposed && unposed->is_array() && !unposed->empty()) {
    std::vector<std::vector<std::string>> unposed_rows;
    for (const Json& frame : *unposed) {
      unposed_rows.push_back({Integer(Number(frame, "image_id")), Text(frame, "reason")});
    }
    page->Table("unposed-table", {"frame without a pose (image id)", "why"}, unposed_rows);
  }
}

void AccuracySection(const RunData& run, Page* page, TrajectoryFigures* figures_out) {
  page->Heading("Accuracy", "accuracy");
  if (!run.ate.Any() && !run.vio_ate.Any()) {
    page->Note("no ground truth: no absolute trajectory error (ATE) was computed.");
  } else {
    std::vector<std::vector<std::string>> rows;
    for (const auto& [name, ate] :
         {std::pair{"viosfm", &run.ate}, std::pair{"input VIO", &run.vio_ate}}) {
      if (!ate->Any()) {
        rows.push_back({name, "n/a", "n/a", "n/a", "n/a", "n/a", "", ""});
        continue;
      }
      rows.push_back({name, FormatFixedOrNa(ate->rmse, 4), FormatFixedOrNa(ate->mean, 4),
                      FormatFixedOrNa(ate->median, 4), FormatFixedOrNa(ate->max, 4),
                      Integer(ate->count), ate->alignment, ate->source});
    }
    page->Table("ate-table",
                {"trajectory", "ATE RMSE (m)", "mean (m)", "median (m)", "max (m)", "poses",
                 "alignment", "from"},
                rows);
  }

  // Metric accuracy (summary.json): what the IMU buys beyond the shape.
  if (Find(run.summary, "eval/metric")) {
    std::vector<std::vector<std::string>> rows;
    for (const auto& [name, key] :
         {std::pair{"viosfm", "eval/metric"}, std::pair{"input VIO", "eval/vio_metric"}}) {
      const std::string k = key;
      const std::optional<double> scale_error = Number(run.summary, k + "/scale_error");
      rows.push_back({name, FormatFixedOrNa(Number(run.summary, k + "/ate_sim3_rmse_m"), 4),
                      FormatFixedOrNa(Number(run.summary, k + "/ate_se3_rmse_m"), 4),
                      FormatFixedOrNa(Number(run.summary, k + "/ate_posyaw_rmse_m"), 4),
                      FormatFixedOrNa(Number(run.summary, k + "/scale"), 4),
                      scale_error ? FormatFixedOrNa(100.0 * *scale_error, 2) : std::string("n/a")});
    }
    page->Paragraph(
        "Metric accuracy: the ATE RMSE after each alignment (Sim(3): the shape; SE(3): shape "
        "and metric scale; position + yaw: also the gravity direction) and the scale of the "
        "trajectory (1 / the Sim(3) alignment's scale).");
    page->Table("metric-table",
                {"trajectory", "ATE Sim(3) (m)", "ATE SE(3) (m)", "ATE pos+yaw (m)", "scale",
                 "scale error (%)"},
                rows);
  }

  page->Heading("Trajectory", "trajectory");
  if (!run.has_estimate) {
    page->Note("no trajectory: trajectory_body.tum is missing or empty.");
    return;
  }
  *figures_out =
      MakeTrajectoryFigures(run.estimate, run.has_ground_truth ? run.ground_truth : Trajectory(),
                            run.has_vio ? run.vio : Trajectory());
  if (!run.has_ground_truth) {
    page->Note("no ground truth: the estimate and the input VIO are drawn in their own frames.");
  } else if (!figures_out->estimate_evaluation) {
    page->Note("the estimate could not be aligned to the ground truth: " +
               figures_out->estimate_alignment_error);
  } else {
    const EvaluationResult& e = *figures_out->estimate_evaluation;
    page->Paragraph(
        "The estimate is aligned to the ground truth by " + AlignmentModeName(e.alignment) +
        " (scale " + FormatFixedOrNa(e.ref_from_est.scale, 4) + ", " +
        std::to_string(e.pairs.size()) + " associated poses) and coloured by its position error.");
  }
  page->Figures({RenderSvg(figures_out->top_view), RenderSvg(figures_out->side_view)});
}

// The folder the run read its images from (RUN/options.json's dataset: a
// EuRoC folder's mav0/cam0/data, a bag's extracted images, or an image
// folder); empty if it cannot be told or is gone.
fs::path ImageFolderOfRun(const RunData& run) {
  if (!run.options || !run.options->is_object()) return {};
  const auto text = [&run](const char* key) -> std::string {
    const auto it = run.options->find(key);
    return it != run.options->end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  const fs::path dataset = text("dataset");
  if (dataset.empty()) return {};
  std::vector<fs::path> candidates;
  if (IsBagPath(dataset)) {
    candidates = {fs::path(text("rosbag.extract_folder")) / "mav0" / "cam0" / "data",
                  run.run_dir / "bag" / "mav0" / "cam0" / "data"};
  } else {
    candidates = {dataset / "mav0" / "cam0" / "data", dataset / "cam0" / "data", dataset};
  }
  std::error_code error;
  for (const fs::path& candidate : candidates) {
    if (!candidate.empty() && fs::is_directory(candidate, error)) return candidate;
  }
  return {};
}

// The frames of RUN/model (COLMAP) as frustums, in the order of their stamps
// (else names), and their camera; the images from the run's dataset.
void AddFrames(const RunData& run, Viewer3dScene* scene) {
  const fs::path model = run.run_dir / "model";
  std::error_code error;
  if (!fs::is_directory(model, error)) return;
  const Reconstruction reconstruction = ReadColmapModel(model);
  const fs::path images = ImageFolderOfRun(run);
  std::vector<const Image*> ordered;
  for (const auto& [id, image] : reconstruction.Images()) {
    if (image.registered) ordered.push_back(&image);
  }
  std::sort(ordered.begin(), ordered.end(), [](const Image* a, const Image* b) {
    const std::optional<timestamp_ns_t> ta = TimestampFromImageName(a->name);
    const std::optional<timestamp_ns_t> tb = TimestampFromImageName(b->name);
    if (ta && tb && *ta != *tb) return *ta < *tb;
    return a->name < b->name;
  });
  std::optional<timestamp_ns_t> first;
  for (const Image* image : ordered) {
    if (!first) first = TimestampFromImageName(image->name);
    Viewer3dFrame frame;
    frame.cam_from_world = image->cam_from_world;
    frame.name = image->name;
    const std::optional<timestamp_ns_t> stamp = TimestampFromImageName(image->name);
    if (stamp && first) frame.time_s = static_cast<double>(*stamp - *first) * 1e-9;
    if (!images.empty()) frame.image_path = images / image->name;
    scene->frames.push_back(std::move(frame));
  }
  if (!ordered.empty()) {
    const auto camera = reconstruction.Cameras().find(ordered.front()->camera_id);
    if (camera != reconstruction.Cameras().end()) scene->camera = camera->second;
  }
}

// The 3D view (report/viewer_3d.h): the points of RUN/points.ply, the
// frames of RUN/model as frustums, and the estimated path, coloured by its
// error when the estimate was aligned to the ground truth (which is then
// drawn in the estimate's frame).
void View3dSection(const RunData& run, const TrajectoryFigures& figures, Page* page) {
  page->Heading("3D view", "view3d");
  Viewer3dOptions options;
#ifdef VIOSFM_THREE_JS_DIR
  options.three_js_dir = VIOSFM_THREE_JS_DIR;
#endif
  if (!HasThreeJs(options)) {
    page->Note("no 3D view: three.js was not found in " + options.three_js_dir.string() +
               " (apt-get install libjs-three).");
    return;
  }
  Viewer3dScene scene;
  const fs::path ply = run.run_dir / "points.ply";
  std::error_code error;
  if (fs::is_regular_file(ply, error)) {
    PlyPoints points = ReadPly(ply);
    scene.points = std::move(points.xyz);
    scene.colors = std::move(points.rgb);
  }
  AddFrames(run, &scene);
  // An images-only model has no gravity; every other run's world is the
  // VIO's or the IMU's, gravity-aligned.
  scene.gravity_up = Text(run.summary, "models/images_only") != "true";
  if (run.has_estimate) {
    if (figures.estimate_evaluation) {
      // The associated poses in the estimate's order, with their errors.
      const EvaluationResult& result = *figures.estimate_evaluation;
      std::vector<std::pair<size_t, double>> errors;
      for (size_t k = 0; k < result.pairs.size(); ++k) {
        errors.emplace_back(result.pairs[k].est_index, result.translation_errors_m[k]);
      }
      std::sort(errors.begin(), errors.end());
      for (const auto& [index, e] : errors) {
        scene.path.push_back(run.estimate.poses[index].world_from_frame.translation);
        scene.path_errors_m.push_back(e);
      }
      const Sim3d est_from_ref = result.ref_from_est.Inverse();
      for (const StampedPose& pose : run.ground_truth.poses) {
        scene.ground_truth_path.push_back(est_from_ref * pose.world_from_frame.translation);
      }
    } else {
      for (const StampedPose& pose : run.estimate.poses) {
        scene.path.push_back(pose.world_from_frame.translation);
      }
    }
  }
  if (scene.points.empty() && scene.path.empty() && scene.frames.empty()) {
    page->Note("no 3D view: points.ply, model/ and trajectory_body.tum are missing or empty.");
    return;
  }
  page->out() << RenderViewer3d(scene, options);
}

double OutlierRatioThreshold(const RunData& run) {
  if (run.verification) {
    if (const Json* options = Find(*run.verification, "options"); options && options->is_object()) {
      for (const auto& [key, value] : options->items()) {
        if (key.find("outlier_ratio") == std::string::npos) continue;
        const std::optional<double> number =
            value.is_number()
                ? std::optional<double>(value.get<double>())
                : (value.is_string() ? ParseDouble(Trim(value.get<std::string>())) : std::nullopt);
        if (number) return *number;
      }
    }
  }
  return kDefaultOutlierRatioThreshold;
}

void VerificationSection(const RunData& run, Page* page) {
  page->Heading("Pair verification", "verification");
  const Json& s = run.summary;
  std::vector<std::pair<std::string, std::string>> rows = {
      {"candidate pairs", Integer(Number(s, "pairs/candidates"))},
      {"accepted", Integer(Number(s, "pairs/accepted"))},
      {"rejected by the VIO prior", Integer(Number(s, "pairs/vio_rejected"))},
      {"rejected by RANSAC", Integer(Number(s, "pairs/ransac_rejected"))},
      {"no tentative matches", Integer(Number(s, "pairs/no_matches"))},
  };
  // Counts the summary holds beyond these (e.g. further rejection checks).
  if (const Json* pairs = Find(s, "pairs"); pairs && pairs->is_object()) {
    for (const auto& [key, value] : pairs->items()) {
      if (key == "candidates" || key == "accepted" || key == "vio_rejected" ||
          key == "ransac_rejected" || key == "no_matches" || !value.is_number()) {
        continue;
      }
      rows.push_back({key, Integer(value.get<double>())});
    }
  }
  if (run.verification) {
    const Json& v = *run.verification;
    rows.push_back(
        {"pairs without VIO prior", Integer(Number(v, "summary/num_pairs_without_prior"))});
    rows.push_back({"pairs resumed from the database", Integer(Number(v, "summary/num_resumed"))});
    rows.push_back(
        {"verification time (s)", FormatFixedOrNa(Number(v, "summary/seconds_total"), 2)});
  }
  page->KeyValueTable("pairs-table", rows);

  if (!run.has_pairs) {
    page->Note(
        "no pair records: verification/pairs.csv and verification/verification.json are missing.");
    return;
  }
  const double threshold = OutlierRatioThreshold(run);
  if (run.outlier_ratios.empty()) {
    page->Note("no VIO outlier ratios: the VIO-prior check ran on no pair.");
    return;
  }
  std::vector<double> counts(kHistogramBins, 0.0);
  const double bin = 1.0 / kHistogramBins;
  size_t above = 0;
  for (double ratio : run.outlier_ratios) {
    const int k = std::clamp(static_cast<int>(std::floor(ratio / bin)), 0, kHistogramBins - 1);
    counts[k] += 1.0;
    if (ratio > threshold) ++above;
  }
  Figure figure;
  figure.title = "VIO outlier ratio of the verified pairs";
  figure.x_label = "outlier ratio under the VIO relative pose";
  figure.y_label = "pairs";
  figure.width = 720;
  figure.height = 340;
  figure.margin_fraction = 0.05;
  Series kept, rejected;
  kept.kind = rejected.kind = SeriesKind::kBars;
  kept.bar_width = rejected.bar_width = bin;
  kept.label = "ratio <= " + FormatFixedOrNa(threshold, 2);
  rejected.label = "ratio > " + FormatFixedOrNa(threshold, 2);
  kept.color = {31, 119, 180};
  rejected.color = {214, 39, 40};
  for (int k = 0; k < kHistogramBins; ++k) {
    const double center = (k + 0.5) * bin;
    Series& series = center <= threshold ? kept : rejected;
    series.x.push_back(center);
    series.y.push_back(counts[k]);
  }
  figure.series = {kept, rejected};
  figure.vertical_lines.push_back(
      {threshold, "threshold " + FormatFixedOrNa(threshold, 2), {60, 60, 60}, true});
  page->Paragraph(std::to_string(run.outlier_ratios.size()) + " pairs with a VIO check (from " +
                  run.pairs_source + "); " + std::to_string(above) + " above the threshold " +
                  FormatFixedOrNa(threshold, 2) + ".");
  page->Figures({RenderSvg(figure)});
}

void TimingSection(const RunData& run, Page* page) {
  page->Heading("Timings", "timings");
  const Json* stages = Find(run.summary, "stages");
  if (stages == nullptr || !stages->is_array() || stages->empty()) {
    page->Note("no stage timings in summary.json.");
  } else {
    BarChart chart;
    chart.title = "Time per stage";
    chart.value_label = "seconds";
    chart.width = 720;
    for (const Json& stage : *stages) {
      chart.names.push_back(Text(stage, "name"));
      chart.values.push_back(Number(stage, "seconds").value_or(0.0));
    }
    page->Paragraph("Total: " + FormatFixedOrNa(Number(run.summary, "total_seconds"), 2) + " s.");
    page->Figures({RenderSvg(chart)});
  }

  page->Heading("Batches", "batches");
  const Json* batches = Find(run.summary, "batches");
  if (batches == nullptr || !batches->is_array() || batches->empty()) {
    page->Note("no batches in summary.json.");
    return;
  }
  std::vector<std::vector<std::string>> rows;
  Series bars;
  bars.kind = SeriesKind::kBars;
  bars.bar_width = 0.8;
  for (const Json& batch : *batches) {
    const std::optional<double> index = Number(batch, "index");
    rows.push_back({Integer(index), Integer(Number(batch, "images")),
                    Integer(Number(batch, "registered_total")),
                    Integer(Number(batch, "points_total")),
                    FormatFixedOrNa(Number(batch, "mean_reprojection_error_px"), 3),
                    FormatFixedOrNa(Number(batch, "seconds_ba"), 2)});
    if (index) {
      bars.x.push_back(*index);
      bars.y.push_back(Number(batch, "seconds_ba").value_or(0.0));
    }
  }
  Figure figure;
  figure.title = "Bundle adjustment time per batch";
  figure.x_label = "batch";
  figure.y_label = "seconds";
  figure.width = 720;
  figure.height = 300;
  figure.margin_fraction = 0.05;
  figure.series.push_back(bars);
  page->Figures({RenderSvg(figure)});
  page->Table("batch-table",
              {"batch", "images", "registered (total)", "points (total)",
               "window reprojection error (px)", "BA time (s)"},
              rows);
}

// Flattens nested objects into "a.b.c" = value rows.
void FlattenJson(const Json& json, const std::string& prefix,
                 std::vector<std::pair<std::string, std::string>>* rows) {
  if (json.is_object()) {
    for (const auto& [key, value] : json.items()) {
      FlattenJson(value, prefix.empty() ? key : prefix + "." + key, rows);
    }
    return;
  }
  rows->push_back({prefix, json.is_string() ? json.get<std::string>() : json.dump()});
}

void OptionsSection(const RunData& run, Page* page) {
  page->Heading("Options", "options");
  if (!run.options) {
    page->Note("no options.json in the run folder.");
    return;
  }
  std::vector<std::pair<std::string, std::string>> rows;
  FlattenJson(*run.options, "", &rows);
  page->KeyValueTable("options-table", rows, "options");
}

}  // namespace

fs::path DefaultReportPath(const fs::path& run_dir) {
  return run_dir / "report.html";
}

std::string RenderRunReport(const fs::path& run_dir) {
  const RunData run = LoadRun(run_dir);
  Page page;
  std::ostringstream& out = page.out();
  const std::string dataset = Text(run.summary, "dataset");
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<title>viosfm report" << (dataset.empty() ? "" : ": " + Escape(dataset))
      << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
  out << "<h1>viosfm run report</h1>\n<p class=\"meta\">dataset <b>"
      << Escape(dataset.empty() ? "(unknown)" : dataset) << "</b> &middot; started "
      << Escape(Text(run.summary, "started_utc")) << " &middot; viosfm "
      << Escape(Text(run.summary, "viosfm_version")) << " &middot; run folder "
      << Escape(run_dir.string()) << "</p>\n";
  DecisionsList(run, &page);
  SummarySection(run, &page);
  TrajectoryFigures figures;
  AccuracySection(run, &page, &figures);
  View3dSection(run, figures, &page);
  VerificationSection(run, &page);
  TimingSection(run, &page);
  OptionsSection(run, &page);
  out << "</body>\n</html>\n";
  return out.str();
}

void WriteRunReport(const fs::path& run_dir, const fs::path& html_path) {
  const std::string html = RenderRunReport(run_dir);
  WriteFileAtomically(html_path, [&html](std::ostream& out) { out << html; });
}

}  // namespace viosfm

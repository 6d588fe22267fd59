#include "viosfm/report/run_plots.h"

#include <algorithm>
#include <utility>

#include "viosfm/util/errors.h"
#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

const Color kGroundTruthColor = {150, 150, 150};
const Color kVioColor = {255, 127, 14};
const Color kEstimateColor = {31, 119, 180};

// Positions of `trajectory` mapped by `ref_from_est`.
std::vector<Eigen::Vector3d> Positions(const Trajectory& trajectory, const Sim3d& ref_from_est) {
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(trajectory.size());
  for (const StampedPose& pose : trajectory.poses) {
    positions.push_back(ref_from_est * pose.world_from_frame.translation);
  }
  return positions;
}

// One series of each view: the views' second axis is y (top) or z (side).
struct ViewSeries {
  Series top;
  Series side;
};

ViewSeries MakeLine(const std::vector<Eigen::Vector3d>& positions, const std::string& label,
                    const Color& color, bool dashed, double width) {
  ViewSeries views;
  views.top.kind = SeriesKind::kLine;
  views.top.label = label;
  views.top.color = color;
  views.top.dashed = dashed;
  views.top.line_width = width;
  for (const Eigen::Vector3d& p : positions) {
    views.top.x.push_back(p.x());
    views.top.y.push_back(p.y());
  }
  views.side = views.top;
  for (size_t i = 0; i < positions.size(); ++i) views.side.y[i] = positions[i].z();
  return views;
}

std::optional<EvaluationResult> TryAlign(const Trajectory& est, const Trajectory& ref,
                                         const TrajectoryPlotOptions& options, std::string* error) {
  EvaluationOptions evaluation;
  evaluation.alignment = options.alignment;
  evaluation.max_dt_ns = options.max_dt_ns;
  evaluation.rpe_delta_frames = 0;
  try {
    return EvaluateTrajectories(est, ref, evaluation);
  } catch (const InputError& e) {
    *error = e.what();
    VIOSFM_LOG(WARNING) << "trajectory plot: no alignment: " << e.what();
    return std::nullopt;
  }
}

Figure BaseView(const TrajectoryPlotOptions& options, const std::string& title,
                const std::string& y_label) {
  Figure figure;
  figure.title = title;
  figure.x_label = "x (m)";
  figure.y_label = y_label;
  figure.width = options.width;
  figure.height = options.height;
  figure.equal_aspect = true;
  figure.margin_fraction = 0.04;
  return figure;
}

}  // namespace

std::string TrajectoryPlotOptions::Validate() const {
  if (max_dt_ns < 0) return "max_dt_ns must be >= 0";
  if (!(width >= 100.0)) return "width must be >= 100 px";
  if (!(height >= 100.0)) return "height must be >= 100 px";
  return "";
}

TrajectoryFigures MakeTrajectoryFigures(const Trajectory& estimate, const Trajectory& ground_truth,
                                        const Trajectory& vio,
                                        const TrajectoryPlotOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid trajectory plot options: " + error);
  }
  TrajectoryFigures figures;
  const std::string alignment = AlignmentModeName(options.alignment);
  const bool has_truth = !ground_truth.empty();
  figures.top_view = BaseView(options, "Top view (x-y)", "y (m)");
  figures.side_view = BaseView(options, "Side view (x-z)", "z (m)");
  std::vector<ViewSeries> layers;

  if (has_truth) {
    layers.push_back(
        MakeLine(Positions(ground_truth, Sim3d()), "ground truth", kGroundTruthColor, false, 2.5));
    if (!estimate.empty()) {
      figures.estimate_evaluation =
          TryAlign(estimate, ground_truth, options, &figures.estimate_alignment_error);
    }
    if (!vio.empty()) {
      figures.vio_evaluation = TryAlign(vio, ground_truth, options, &figures.vio_alignment_error);
    }
  }

  if (!vio.empty()) {
    const Sim3d ref_from_vio =
        figures.vio_evaluation ? figures.vio_evaluation->ref_from_est : Sim3d();
    const std::string label =
        figures.vio_evaluation ? "input VIO (" + alignment + "-aligned)" : "input VIO";
    layers.push_back(MakeLine(Positions(vio, ref_from_vio), label, kVioColor, true, 1.5));
  }

  if (figures.estimate_evaluation) {
    // The associated estimate poses, in the estimate's order, coloured by error.
    const EvaluationResult& result = *figures.estimate_evaluation;
    std::vector<std::pair<size_t, double>> errors;  // (est index, error m)
    for (size_t k = 0; k < result.pairs.size(); ++k) {
      errors.emplace_back(result.pairs[k].est_index, result.translation_errors_m[k]);
    }
    std::sort(errors.begin(), errors.end());
    ViewSeries views;
    views.top.kind = SeriesKind::kColoredLine;
    views.top.label = options.estimate_label + " (" + alignment + "-aligned)";
    views.top.line_width = 2.5;
    for (const auto& [index, error] : errors) {
      const Eigen::Vector3d p =
          result.ref_from_est * estimate.poses[index].world_from_frame.translation;
      views.top.x.push_back(p.x());
      views.top.y.push_back(p.y());
      views.top.values.push_back(error);
    }
    views.side = views.top;
    for (size_t i = 0; i < errors.size(); ++i) {
      views.side.y[i] =
          (result.ref_from_est * estimate.poses[errors[i].first].world_from_frame.translation).z();
    }
    layers.push_back(std::move(views));
    for (Figure* figure : {&figures.top_view, &figures.side_view}) {
      figure->colorbar_label = "position error (m)";
      figure->color_min = 0.0;
    }
  } else if (!estimate.empty()) {
    layers.push_back(
        MakeLine(Positions(estimate, Sim3d()), options.estimate_label, kEstimateColor, false, 2.0));
  }

  for (ViewSeries& layer : layers) {
    figures.top_view.series.push_back(std::move(layer.top));
    figures.side_view.series.push_back(std::move(layer.side));
  }
  return figures;
}

BatchSizeFigures MakeBatchSizeFigures(const BatchSizeSweep& sweep) {
  BatchSizeFigures figures;
  const auto base = [&sweep](const std::string& title, const std::string& y_label) {
    Figure figure;
    figure.title = title;
    figure.x_label = "batch size (images)";
    figure.y_label = y_label;
    figure.width = sweep.width;
    figure.height = sweep.height;
    figure.log_x = sweep.log_x;
    figure.y_from_zero = true;
    figure.margin_fraction = 0.04;
    // The reference lines' labels are written at their right ends.
    figure.legend_right = false;
    return figure;
  };
  figures.ate = base("Trajectory RMSE vs batch size", "ATE RMSE (m)");
  figures.time = base("Execution time vs batch size", "time (s)");

  for (size_t c = 0; c < sweep.curves.size(); ++c) {
    const BatchSizeCurve& curve = sweep.curves[c];
    const size_t n = curve.batch_sizes.size();
    if (curve.ate_rmse_m.size() != n || curve.seconds.size() != n) {
      throw InputError("batch-size curve '" + curve.label + "': " + std::to_string(n) +
                       " batch sizes but " + std::to_string(curve.ate_rmse_m.size()) +
                       " ATE values and " + std::to_string(curve.seconds.size()) + " times");
    }
    const Color color = PaletteColor(static_cast<int>(c));
    for (auto [figure, values] :
         {std::pair{&figures.ate, &curve.ate_rmse_m}, std::pair{&figures.time, &curve.seconds}}) {
      Series line;
      line.kind = SeriesKind::kLine;
      line.label = curve.label;
      line.color = color;
      line.x = curve.batch_sizes;
      line.y = *values;
      Series markers = line;
      markers.kind = SeriesKind::kScatter;
      markers.label.clear();
      figure->series.push_back(std::move(line));
      figure->series.push_back(std::move(markers));
    }
  }
  const auto add_references = [](const std::vector<ReferenceValue>& references, Figure* figure) {
    for (size_t i = 0; i < references.size(); ++i) {
      ReferenceLine line;
      line.value = references[i].value;
      line.label = references[i].label;
      line.color = i == 0 ? Color{200, 30, 30} : PaletteColor(static_cast<int>(i) + 3);
      line.dashed = true;
      figure->horizontal_lines.push_back(line);
    }
  };
  add_references(sweep.ate_references, &figures.ate);
  add_references(sweep.time_references, &figures.time);
  return figures;
}

}  // namespace viosfm

#include "viosfm/report/eval_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

const Color kReferenceColor = {128, 128, 128};
const Color kErrorColor = {70, 70, 70};
const Color kRmseColor = {214, 39, 40};
const Color kMedianColor = {44, 160, 44};
const Color kMeanColor = {31, 119, 180};
const Color kBarColor = {31, 119, 180};

std::string Value(double value, const std::string& unit) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.4g %s", value, unit.c_str());
  return buffer;
}

Figure Base(const EvaluationPlotOptions& options, const std::string& title,
            const std::string& x_label, const std::string& y_label) {
  Figure figure;
  figure.title = title;
  figure.x_label = x_label;
  figure.y_label = y_label;
  figure.width = options.width;
  figure.height = options.height;
  figure.margin_fraction = 0.04;
  return figure;
}

// RMSE, median and mean as labelled horizontal (or vertical) lines.
std::vector<ReferenceLine> StatisticLines(const ErrorStatistics& stats, const std::string& unit) {
  return {{stats.rmse, "rmse " + Value(stats.rmse, unit), kRmseColor, true},
          {stats.median, "median " + Value(stats.median, unit), kMedianColor, true},
          {stats.mean, "mean " + Value(stats.mean, unit), kMeanColor, true}};
}

// The statistics' lines lie close together, so their labels would overlap:
// the legend names them instead (a dashed key each, no data).
void NameLinesInLegend(std::vector<ReferenceLine>* lines, Figure* figure) {
  for (ReferenceLine& line : *lines) {
    Series key;
    key.kind = SeriesKind::kLine;
    key.dashed = true;
    key.color = line.color;
    key.label = line.label;
    figure->series.push_back(std::move(key));
    line.label.clear();
  }
}

// Seconds since `t0` of each stamp, or the index without stamps.
double TimeAxis(const Trajectory& trajectory, size_t index, timestamp_ns_t t0) {
  return trajectory.has_timestamps
             ? static_cast<double>(trajectory.poses[index].timestamp_ns - t0) * 1e-9
             : static_cast<double>(index);
}

void AddTrajectoryViews(const Trajectory& est, const Trajectory& ref,
                        const EvaluationResult& result, const EvaluationPlotOptions& options,
                        std::vector<NamedFigure>* figures) {
  const std::string alignment = AlignmentModeName(result.alignment);
  // (axis index of the figure's y, its name)
  for (const auto& [name, axis, title] :
       {std::tuple{"trajectory_top", 1, "Trajectories from above (x-y)"},
        std::tuple{"trajectory_side", 2, "Trajectories from the side (x-z)"}}) {
    Figure figure = Base(options, title, "x (m)", axis == 1 ? "y (m)" : "z (m)");
    figure.equal_aspect = true;
    figure.colorbar_label = "position error (m)";
    figure.color_min = 0.0;
    Series reference;
    reference.kind = SeriesKind::kLine;
    reference.label = options.reference_label;
    reference.color = kReferenceColor;
    reference.dashed = true;
    reference.line_width = 1.5;
    for (const StampedPose& pose : ref.poses) {
      reference.x.push_back(pose.world_from_frame.translation.x());
      reference.y.push_back(pose.world_from_frame.translation[axis]);
    }
    Series estimate;
    estimate.kind = SeriesKind::kColoredLine;
    estimate.label = options.estimate_label + " (" + alignment + "-aligned)";
    estimate.line_width = 2.5;
    // The associated poses in the estimate's order.
    std::vector<std::pair<size_t, double>> errors;
    for (size_t k = 0; k < result.pairs.size(); ++k) {
      errors.emplace_back(result.pairs[k].est_index, result.translation_errors_m[k]);
    }
    std::sort(errors.begin(), errors.end());
    for (const auto& [index, error] : errors) {
      const Eigen::Vector3d p = result.ref_from_est * est.poses[index].world_from_frame.translation;
      estimate.x.push_back(p.x());
      estimate.y.push_back(p[axis]);
      estimate.values.push_back(error);
    }
    figure.series = {std::move(reference), std::move(estimate)};
    figures->push_back({name, std::move(figure)});
  }
}

void AddErrorOverTime(const Trajectory& ref, const EvaluationResult& result,
                      const EvaluationPlotOptions& options, std::vector<NamedFigure>* figures) {
  const timestamp_ns_t t0 = ref.poses.front().timestamp_ns;
  Figure figure =
      Base(options,
           "Position error over time (ATE, " + AlignmentModeName(result.alignment) + "-aligned)",
           ref.has_timestamps ? "t (s)" : "pose index", "position error (m)");
  figure.y_from_zero = true;
  figure.legend_right = false;
  std::vector<std::pair<double, double>> points;
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    points.emplace_back(TimeAxis(ref, result.pairs[k].ref_index, t0),
                        result.translation_errors_m[k]);
  }
  std::sort(points.begin(), points.end());
  Series error;
  error.kind = SeriesKind::kLine;
  error.label = "position error";
  error.color = kErrorColor;
  error.line_width = 1.5;
  for (const auto& [t, e] : points) {
    error.x.push_back(t);
    error.y.push_back(e);
  }
  figure.series.push_back(std::move(error));
  figure.horizontal_lines = StatisticLines(result.ate_translation_m, "m");
  NameLinesInLegend(&figure.horizontal_lines, &figure);
  figures->push_back({"error_over_time", std::move(figure)});
}

void AddHistogram(const EvaluationResult& result, const EvaluationPlotOptions& options,
                  std::vector<NamedFigure>* figures) {
  const std::vector<double>& errors = result.translation_errors_m;
  const ErrorStatistics& stats = result.ate_translation_m;
  const int bins =
      options.histogram_bins > 0
          ? options.histogram_bins
          : std::clamp(static_cast<int>(std::lround(std::sqrt(errors.size()))), 10, 60);
  const double top = stats.max > 0.0 ? stats.max : 1.0;
  const double width = top / bins;
  std::vector<double> counts(bins, 0.0);
  for (const double e : errors) {
    counts[std::clamp(static_cast<int>(std::floor(e / width)), 0, bins - 1)] += 1.0;
  }
  Figure figure =
      Base(options, "Position error histogram (" + std::to_string(errors.size()) + " poses)",
           "position error (m)", "poses");
  Series bars;
  bars.kind = SeriesKind::kBars;
  bars.color = kBarColor;
  bars.bar_width = width;
  for (int k = 0; k < bins; ++k) {
    bars.x.push_back((k + 0.5) * width);
    bars.y.push_back(counts[k]);
  }
  figure.series.push_back(std::move(bars));
  figure.vertical_lines = StatisticLines(stats, "m");
  NameLinesInLegend(&figure.vertical_lines, &figure);
  figures->push_back({"error_histogram", std::move(figure)});
}

void AddGyroErrors(const GyroCheckResult& gyro, const EvaluationPlotOptions& options,
                   std::vector<NamedFigure>* figures) {
  if (gyro.intervals.empty()) return;
  const timestamp_ns_t t0 = gyro.intervals.front().from_ns;
  char offset[64];
  std::snprintf(offset, sizeof(offset), "%.2f", static_cast<double>(gyro.time_offset_ns) * 1e-6);
  Figure figure =
      Base(options, "Rotation against the gyro (time offset " + std::string(offset) + " ms)",
           "t (s)", "rotation error (deg)");
  figure.y_from_zero = true;
  figure.legend_right = false;
  Series error;
  error.kind = SeriesKind::kLine;
  error.label = "error over each interval";
  error.color = kErrorColor;
  Series markers;
  markers.kind = SeriesKind::kScatter;
  markers.color = kErrorColor;
  markers.marker_radius = 2.0;
  for (const GyroCheckInterval& interval : gyro.intervals) {
    const double t = 0.5 * static_cast<double>(interval.from_ns + interval.to_ns - 2 * t0) * 1e-9;
    error.x.push_back(t);
    error.y.push_back(interval.error_deg);
  }
  markers.x = error.x;
  markers.y = error.y;
  figure.series = {std::move(error), std::move(markers)};
  figure.horizontal_lines = StatisticLines(gyro.error_deg, "deg");
  NameLinesInLegend(&figure.horizontal_lines, &figure);
  figures->push_back({"gyro_error_over_time", std::move(figure)});
}

}  // namespace

std::string EvaluationPlotOptions::Validate() const {
  if (!(width >= 200.0) || !(height >= 150.0)) return "width and height must be >= 200 x 150 px";
  if (histogram_bins < 0) return "histogram_bins must be >= 0";
  return "";
}

std::vector<NamedFigure> MakeEvaluationFigures(const Trajectory& est, const Trajectory& ref,
                                               const EvaluationResult* result,
                                               const GyroCheckResult* gyro,
                                               const EvaluationPlotOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("invalid plot options: " + error);
  }
  std::vector<NamedFigure> figures;
  if (result != nullptr && !result->pairs.empty() && !ref.empty()) {
    for (const PosePair& pair : result->pairs) {
      if (pair.est_index >= est.size() || pair.ref_index >= ref.size()) {
        throw InputError("the evaluation's pose pairs do not index the trajectories given");
      }
    }
    if (result->translation_errors_m.size() != result->pairs.size()) {
      throw InputError("the evaluation has " + std::to_string(result->pairs.size()) +
                       " pairs but " + std::to_string(result->translation_errors_m.size()) +
                       " errors");
    }
    AddTrajectoryViews(est, ref, *result, options, &figures);
    AddErrorOverTime(ref, *result, options, &figures);
    AddHistogram(*result, options, &figures);
  }
  if (gyro != nullptr) AddGyroErrors(*gyro, options, &figures);
  return figures;
}

std::vector<std::filesystem::path> WriteFigures(const std::filesystem::path& folder,
                                                const std::vector<NamedFigure>& figures) {
  std::filesystem::create_directories(folder);
  std::vector<std::filesystem::path> written;
  for (const NamedFigure& named : figures) {
    const std::filesystem::path svg = folder / (named.name + ".svg");
    const std::filesystem::path png = folder / (named.name + ".png");
    WriteSvg(svg, named.figure);
    WritePng(png, named.figure);
    written.push_back(svg);
    written.push_back(png);
  }
  return written;
}

}  // namespace viosfm

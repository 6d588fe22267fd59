#include "viosfm/report/eval_plots.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

#include "viosfm/util/file_util.h"
#include "viosfm/util/string_util.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

struct Box {
  double min_x = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();
  void Add(double x, double y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
};

// A 20 s reference on an ellipse 6 m x 3 m, rising 1 m, at 20 Hz; the
// estimate is the same path in a frame rotated about z by 30 degrees,
// shifted by (5, -2, 1) m and scaled by 0.5, with 1 cm of noise; its
// stamps are 1 ms later (associated within the 10 ms tolerance).
struct Scenario {
  Trajectory ref;
  Trajectory est;
};

Scenario MakeScenario() {
  Scenario s;
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d shift(5.0, -2.0, 1.0);
  for (int i = 0; i < 400; ++i) {
    const double t = i * 0.05;
    const double angle = 2.0 * M_PI * t / 20.0;
    const Eigen::Vector3d p(3.0 * std::cos(angle), 1.5 * std::sin(angle), 0.05 * t);
    StampedPose ref_pose;
    ref_pose.timestamp_ns = 1'000'000'000 + static_cast<timestamp_ns_t>(i) * 50'000'000;
    ref_pose.world_from_frame =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())), p);
    s.ref.poses.push_back(ref_pose);
    const Eigen::Vector3d noisy = p + Eigen::Vector3d(noise(random), noise(random), noise(random));
    StampedPose est_pose;
    est_pose.timestamp_ns = ref_pose.timestamp_ns + 1'000'000;
    est_pose.world_from_frame =
        Rigid3d(Eigen::Quaterniond(rotation) * ref_pose.world_from_frame.rotation,
                0.5 * (rotation * noisy) + shift);
    s.est.poses.push_back(est_pose);
  }
  return s;
}

const NamedFigure& Find(const std::vector<NamedFigure>& figures, const std::string& name) {
  for (const NamedFigure& figure : figures) {
    if (figure.name == name) return figure;
  }
  ADD_FAILURE() << "no figure " << name;
  static const NamedFigure kNone;
  return kNone;
}

EvaluationResult Evaluate(const Scenario& s) {
  EvaluationOptions options;
  options.alignment = AlignmentMode::kSim3;
  return EvaluateTrajectories(s.est, s.ref, options);
}

// The overlays show the reference as given and the estimate after the
// evaluation's Sim(3) alignment: both cover the same extent (the ellipse's
// 6 m x 3 m from above, its 1 m rise from the side), which they would not
// if the estimate were drawn in its own frame (half the size, rotated).
TEST(MakeEvaluationFigures, OverlaysCoverTheReferenceExtents) {
  const Scenario s = MakeScenario();
  const EvaluationResult result = Evaluate(s);
  ASSERT_EQ(result.pairs.size(), 400u);
  const std::vector<NamedFigure> figures = MakeEvaluationFigures(s.est, s.ref, &result, nullptr);
  ASSERT_EQ(figures.size(), 4u);
  for (const auto& [name, axis] :
       {std::pair{"trajectory_top", 1}, std::pair{"trajectory_side", 2}}) {
    const Figure& figure = Find(figures, name).figure;
    ASSERT_EQ(figure.series.size(), 2u) << name;
    const Series& reference = figure.series[0];
    const Series& estimate = figure.series[1];
    EXPECT_EQ(estimate.kind, SeriesKind::kColoredLine);
    ASSERT_EQ(reference.x.size(), 400u);
    ASSERT_EQ(estimate.x.size(), 400u);
    ASSERT_EQ(estimate.values.size(), 400u);
    Box ref_box, est_box, truth;
    for (size_t i = 0; i < 400; ++i) {
      ref_box.Add(reference.x[i], reference.y[i]);
      est_box.Add(estimate.x[i], estimate.y[i]);
      const Eigen::Vector3d& p = s.ref.poses[i].world_from_frame.translation;
      truth.Add(p.x(), p[axis]);
    }
    EXPECT_NEAR(ref_box.min_x, truth.min_x, 1e-12) << name;
    EXPECT_NEAR(ref_box.max_y, truth.max_y, 1e-12) << name;
    // The aligned estimate's extent: that of the reference within the noise.
    EXPECT_NEAR(est_box.min_x, truth.min_x, 0.05) << name;
    EXPECT_NEAR(est_box.max_x, truth.max_x, 0.05) << name;
    EXPECT_NEAR(est_box.min_y, truth.min_y, 0.05) << name;
    EXPECT_NEAR(est_box.max_y, truth.max_y, 0.05) << name;
    // Colours: the per-pose errors, largest equal to the ATE's maximum.
    EXPECT_DOUBLE_EQ(*std::max_element(estimate.values.begin(), estimate.values.end()),
                     result.ate_translation_m.max);
  }
  EXPECT_TRUE(Find(figures, "trajectory_top").figure.equal_aspect);
}

// Error over time spans the recording's 19.95 s and plots the ATE's errors;
// the histogram counts every pose once and its bins cover 0 to the maximum.
TEST(MakeEvaluationFigures, ErrorOverTimeAndHistogramHoldEveryPose) {
  const Scenario s = MakeScenario();
  const EvaluationResult result = Evaluate(s);
  const std::vector<NamedFigure> figures = MakeEvaluationFigures(s.est, s.ref, &result, nullptr);
  const Figure& over_time = Find(figures, "error_over_time").figure;
  ASSERT_GE(over_time.series.size(), 1u);
  const Series& error = over_time.series[0];
  ASSERT_EQ(error.x.size(), 400u);
  EXPECT_NEAR(error.x.front(), 0.0, 1e-9);
  EXPECT_NEAR(error.x.back(), 19.95, 1e-9);
  EXPECT_TRUE(std::is_sorted(error.x.begin(), error.x.end()));
  std::vector<double> plotted = error.y, expected = result.translation_errors_m;
  std::sort(plotted.begin(), plotted.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(plotted, expected);
  ASSERT_EQ(over_time.horizontal_lines.size(), 3u);
  EXPECT_DOUBLE_EQ(over_time.horizontal_lines[0].value, result.ate_translation_m.rmse);
  // 1 cm of noise a coordinate, halved by the estimate's scale and doubled
  // back by the alignment: an RMSE near sqrt(3) cm.
  EXPECT_NEAR(result.ate_translation_m.rmse, std::sqrt(3.0) * 0.01, 0.004);

  const Figure& histogram = Find(figures, "error_histogram").figure;
  ASSERT_EQ(histogram.series.size(), 4u);  // the bars, then the statistics' legend keys
  const Series& bars = histogram.series[0];
  EXPECT_EQ(bars.kind, SeriesKind::kBars);
  EXPECT_EQ(bars.x.size(), 20u);  // sqrt(400)
  double total = 0.0;
  for (const double count : bars.y) total += count;
  EXPECT_DOUBLE_EQ(total, 400.0);
  EXPECT_NEAR(bars.x.back() + 0.5 * bars.bar_width, result.ate_translation_m.max, 1e-12);
  EXPECT_NEAR(bars.x.front() - 0.5 * bars.bar_width, 0.0, 1e-12);
}

// A gyro check alone gives its figure only, titled with its time offset.
TEST(MakeEvaluationFigures, GyroFigureNamesTheTimeOffset) {
  GyroCheckResult gyro;
  gyro.time_offset_ns = -47'300'000;
  for (int i = 0; i < 10; ++i) {
    gyro.intervals.push_back({1'000'000'000LL * i, 1'000'000'000LL * (i + 1), 10.0, 0.1 * i});
  }
  gyro.error_deg = ComputeErrorStatistics({0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9});
  const std::vector<NamedFigure> figures =
      MakeEvaluationFigures(Trajectory(), Trajectory(), nullptr, &gyro);
  ASSERT_EQ(figures.size(), 1u);
  EXPECT_EQ(figures[0].name, "gyro_error_over_time");
  EXPECT_NE(figures[0].figure.title.find("time offset -47.30 ms"), std::string::npos)
      << figures[0].figure.title;
  EXPECT_NEAR(figures[0].figure.series[0].x.front(), 0.5, 1e-12);  // the interval's middle
  EXPECT_NEAR(figures[0].figure.series[0].y.back(), 0.9, 1e-12);
}

TEST(MakeEvaluationFigures, PairsOutsideTheTrajectoriesAreRefused) {
  const Scenario s = MakeScenario();
  EvaluationResult result = Evaluate(s);
  Trajectory shorter = s.est;
  shorter.poses.resize(100);
  testing::ExpectInputError([&] { MakeEvaluationFigures(shorter, s.ref, &result, nullptr); });
  EvaluationPlotOptions bad;
  bad.width = 10;
  testing::ExpectInputError([&] { MakeEvaluationFigures(s.est, s.ref, &result, nullptr, bad); });
}

// Both files of each figure are written; the PNG is the SVG's layout drawn at
// twice the size: the estimate's coloured pixels span the box its SVG
// segments span (doubled).
TEST(WriteFigures, PngDrawsTheSvgLayout) {
  const Scenario s = MakeScenario();
  const EvaluationResult result = Evaluate(s);
  const std::vector<NamedFigure> figures = MakeEvaluationFigures(s.est, s.ref, &result, nullptr);
  const fs::path folder = testing::MakeScratchFolder("eval_plots") / "plots";
  const std::vector<fs::path> written = WriteFigures(folder, figures);
  ASSERT_EQ(written.size(), 8u);
  for (const fs::path& path : written) EXPECT_TRUE(fs::is_regular_file(path)) << path;

  const cv::Mat written_png =
      cv::imread((folder / "trajectory_top.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(written_png.empty());

  // Without the legend (whose key is coloured too), the same figure as SVG
  // and PNG.
  Figure top = Find(figures, "trajectory_top").figure;
  EXPECT_EQ(written_png.cols, static_cast<int>(2 * top.width));
  EXPECT_EQ(written_png.rows, static_cast<int>(2 * top.height));
  for (Series& series : top.series) series.label.clear();
  // The SVG's coloured segments (the estimate): their points' box.
  const std::string svg = RenderSvg(top);
  Box svg_box;
  size_t segments = 0;
  for (size_t at = svg.find("<polyline"); at != std::string::npos;
       at = svg.find("<polyline", at + 1)) {
    const size_t end = svg.find('>', at);
    const std::string tag = svg.substr(at, end - at);
    const size_t stroke = tag.find("stroke=\"#");
    if (stroke == std::string::npos || tag.find("stroke-dasharray") != std::string::npos) continue;
    const size_t points_at = tag.find("points=\"");
    if (points_at == std::string::npos) continue;
    const std::string hex = tag.substr(stroke + 8, 7);
    // Dark lines (axes, text) are not the estimate.
    if (hex == "#000000" || hex == "#808080" || hex == "#464646") continue;
    ++segments;
    const std::string points =
        tag.substr(points_at + 8, tag.find('"', points_at + 8) - points_at - 8);
    const std::vector<std::string_view> numbers = Split(points, " ,", true);
    for (size_t k = 0; k + 1 < numbers.size(); k += 2) {
      svg_box.Add(std::stod(std::string(numbers[k])), std::stod(std::string(numbers[k + 1])));
    }
  }
  ASSERT_GT(segments, 5u);

  const std::vector<uint8_t> bytes = RenderPng(top);
  const cv::Mat png = cv::imdecode(bytes, cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  // Saturated pixels (|r - b| large) in the plot area's columns: the
  // estimate's viridis colours; the colour bar to the right is left out by
  // keeping x within the SVG box plus a margin.
  Box png_box;
  for (int y = 0; y < png.rows; ++y) {
    for (int x = 0; x < png.cols; ++x) {
      const cv::Vec3b bgr = png.at<cv::Vec3b>(y, x);
      const int spread = std::max({bgr[0], bgr[1], bgr[2]}) - std::min({bgr[0], bgr[1], bgr[2]});
      if (spread < 60) continue;
      if (x > 2 * svg_box.max_x + 20) continue;  // the colour bar and legend keys
      png_box.Add(x, y);
    }
  }
  EXPECT_NEAR(png_box.min_x, 2 * svg_box.min_x, 8.0);
  EXPECT_NEAR(png_box.max_x, 2 * svg_box.max_x, 8.0);
  EXPECT_NEAR(png_box.min_y, 2 * svg_box.min_y, 8.0);
  EXPECT_NEAR(png_box.max_y, 2 * svg_box.max_y, 8.0);
}

}  // namespace
}  // namespace viosfm

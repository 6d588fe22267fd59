#include "viosfm/report/run_plots.h"

#include <gtest/gtest.h>

#include <cmath>

#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

// A loop with some height change, 10 Hz, in the ground truth's world frame.
Trajectory MakeGroundTruth(int n) {
  Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    StampedPose pose;
    pose.timestamp_ns = 1'000'000'000LL + i * 100'000'000LL;
    pose.world_from_frame.translation =
        Eigen::Vector3d(3.0 * std::cos(a), 2.0 * std::sin(a), 0.5 * std::sin(2.0 * a));
    pose.world_from_frame.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    trajectory.poses.push_back(pose);
  }
  return trajectory;
}

// `truth` moved into another frame by a similarity (as a monocular estimate is).
Trajectory Transform(const Trajectory& truth, const Sim3d& est_from_ref) {
  Trajectory out = truth;
  for (StampedPose& pose : out.poses) {
    pose.world_from_frame = est_from_ref.TransformPose(pose.world_from_frame);
  }
  return out;
}

const Series* FindSeries(const Figure& figure, SeriesKind kind) {
  for (const Series& s : figure.series) {
    if (s.kind == kind) return &s;
  }
  return nullptr;
}

TEST(MakeTrajectoryFigures, AlignsEstimateAndColoursByError) {
  const Trajectory truth = MakeGroundTruth(60);
  const Sim3d est_from_ref(
      0.4, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(5.0, -1.0, 2.0));
  Trajectory estimate = Transform(truth, est_from_ref);
  // One pose off by 0.2 m in the ground truth's scale (0.08 in the estimate's).
  estimate.poses[17].world_from_frame.translation +=
      est_from_ref.rotation * Eigen::Vector3d(0, 0, 0.08);
  // Every other ground-truth pose: the VIO is shorter and exactly in the truth's frame.
  Trajectory vio;
  for (size_t i = 0; i < truth.size(); i += 2) vio.poses.push_back(truth.poses[i]);

  const TrajectoryFigures figures = MakeTrajectoryFigures(estimate, truth, vio);
  ASSERT_TRUE(figures.estimate_evaluation.has_value());
  ASSERT_TRUE(figures.vio_evaluation.has_value());
  EXPECT_TRUE(figures.estimate_alignment_error.empty());
  EXPECT_NEAR(figures.estimate_evaluation->ref_from_est.scale, 1.0 / 0.4, 0.02);

  for (const Figure* view : {&figures.top_view, &figures.side_view}) {
    EXPECT_TRUE(view->equal_aspect);
    ASSERT_EQ(view->series.size(), 3u);  // truth, VIO, estimate
    const Series& truth_line = view->series[0];
    EXPECT_EQ(truth_line.label, "ground truth");
    EXPECT_EQ(truth_line.x.size(), truth.size());
    const Series& vio_line = view->series[1];
    EXPECT_TRUE(vio_line.dashed);
    EXPECT_EQ(vio_line.x.size(), vio.size());
    const Series* colored = FindSeries(*view, SeriesKind::kColoredLine);
    ASSERT_NE(colored, nullptr);
    EXPECT_EQ(colored->label, "viosfm (sim3-aligned)");
    ASSERT_EQ(colored->values.size(), truth.size());
    EXPECT_EQ(view->colorbar_label, "position error (m)");
    // The largest error is the perturbed pose's; the aligned estimate lies
    // on the ground truth elsewhere (within the alignment's spread of it).
    const size_t worst =
        std::max_element(colored->values.begin(), colored->values.end()) - colored->values.begin();
    EXPECT_EQ(worst, 17u);
    EXPECT_NEAR(colored->values[17], 0.2, 0.02);
    for (size_t i = 0; i < truth.size(); ++i) {
      if (i == 17) continue;
      EXPECT_LT(colored->values[i], 0.01) << i;
      EXPECT_NEAR(colored->x[i], truth_line.x[i], 0.01);
      EXPECT_NEAR(colored->y[i], truth_line.y[i], 0.01);
    }
  }
  // Side view holds z.
  EXPECT_NEAR(figures.side_view.series[0].y[5], truth.poses[5].world_from_frame.translation.z(),
              1e-12);
}

TEST(MakeTrajectoryFigures, WithoutGroundTruthDrawsAsIs) {
  const Trajectory estimate = MakeGroundTruth(20);
  const TrajectoryFigures figures = MakeTrajectoryFigures(estimate, Trajectory(), Trajectory());
  EXPECT_FALSE(figures.estimate_evaluation.has_value());
  ASSERT_EQ(figures.top_view.series.size(), 1u);
  EXPECT_EQ(figures.top_view.series[0].kind, SeriesKind::kLine);
  EXPECT_DOUBLE_EQ(figures.top_view.series[0].x[3],
                   estimate.poses[3].world_from_frame.translation.x());
  EXPECT_TRUE(figures.top_view.colorbar_label.empty());
}

TEST(MakeTrajectoryFigures, UnassociatedEstimateFallsBackToPlainLine) {
  const Trajectory truth = MakeGroundTruth(20);
  Trajectory estimate = truth;
  for (StampedPose& pose : estimate.poses) pose.timestamp_ns += 50'000'000'000LL;  // no overlap
  const TrajectoryFigures figures = MakeTrajectoryFigures(estimate, truth, Trajectory());
  EXPECT_FALSE(figures.estimate_evaluation.has_value());
  EXPECT_FALSE(figures.estimate_alignment_error.empty());
  ASSERT_EQ(figures.top_view.series.size(), 2u);
  EXPECT_EQ(figures.top_view.series[1].label, "viosfm");
}

// Another tool's trajectory (the benchmark report's COLMAP rows) carries its own name.
TEST(MakeTrajectoryFigures, EstimateLabelNamesTheTool) {
  const Trajectory truth = MakeGroundTruth(20);
  TrajectoryPlotOptions options;
  options.estimate_label = "COLMAP 3.8";
  const TrajectoryFigures aligned = MakeTrajectoryFigures(truth, truth, Trajectory(), options);
  const Series* colored = FindSeries(aligned.top_view, SeriesKind::kColoredLine);
  ASSERT_NE(colored, nullptr);
  EXPECT_EQ(colored->label, "COLMAP 3.8 (sim3-aligned)");
  const TrajectoryFigures plain = MakeTrajectoryFigures(truth, Trajectory(), Trajectory(), options);
  ASSERT_EQ(plain.top_view.series.size(), 1u);
  EXPECT_EQ(plain.top_view.series[0].label, "COLMAP 3.8");
}

TEST(MakeTrajectoryFigures, RejectsInvalidOptions) {
  TrajectoryPlotOptions options;
  options.width = 3.0;
  EXPECT_NE(testing::InputErrorMessage([&] {
              MakeTrajectoryFigures(MakeGroundTruth(5), Trajectory(), Trajectory(), options);
            }).find("width"),
            std::string::npos);
}

TEST(MakeBatchSizeFigures, CurvesAndReferenceLines) {
  BatchSizeSweep sweep;
  sweep.curves.push_back(
      {"MH_01", {50, 100, 200, 400}, {0.05, 0.04, 0.045, 0.06}, {120, 80, 70, 65}});
  sweep.curves.push_back(
      {"V1_02", {50, 100, 200, 400}, {0.08, 0.07, 0.07, 0.09}, {90, 60, 50, 45}});
  sweep.ate_references.push_back({"COLMAP", 0.055});
  sweep.time_references.push_back({"COLMAP", 300.0});
  sweep.log_x = true;
  const BatchSizeFigures figures = MakeBatchSizeFigures(sweep);
  EXPECT_TRUE(figures.ate.log_x);
  ASSERT_EQ(figures.ate.series.size(), 4u);  // a line and its markers a curve
  EXPECT_EQ(figures.ate.series[0].label, "MH_01");
  EXPECT_EQ(figures.ate.series[2].y[1], 0.07);
  EXPECT_EQ(figures.time.series[2].y[3], 45.0);
  ASSERT_EQ(figures.ate.horizontal_lines.size(), 1u);
  EXPECT_EQ(figures.ate.horizontal_lines[0].value, 0.055);
  EXPECT_EQ(figures.time.horizontal_lines[0].value, 300.0);
  EXPECT_NE(RenderSvg(figures.time).find(">COLMAP</text>"), std::string::npos);

  sweep.curves[1].seconds.pop_back();
  EXPECT_NE(testing::InputErrorMessage([&] { MakeBatchSizeFigures(sweep); }).find("V1_02"),
            std::string::npos);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sfm/linear_solver_chooser.h"

#include <gtest/gtest.h>

#include <cmath>

namespace viosfm {
namespace {

BundleAdjustmentSummary Measured(BaLinearSolver solver, double time_s, int num_iterations,
                                 int num_observations) {
  BundleAdjustmentSummary summary;
  summary.linear_solver = solver;
  summary.time_s = time_s;
  summary.num_iterations = num_iterations;
  summary.num_observations = num_observations;
  return summary;
}

BundleAdjustmentOptions AutoOptions() {
  BundleAdjustmentOptions options;
  options.linear_solver = BaLinearSolver::kAuto;
  options.max_images_for_sparse_schur = 100;
  return options;
}

TEST(LinearSolverChooserTest, SmallProblemsAndForcedSolversAreNotMeasured) {
  LinearSolverChooser chooser(AutoOptions());
  EXPECT_EQ(chooser.Next(100, false), BaLinearSolver::kSparseSchur);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.0, 10, 1000), 100);
  EXPECT_FALSE(chooser.PredictedCost(BaLinearSolver::kSparseSchur, 200).has_value());

  BundleAdjustmentOptions forced = AutoOptions();
  forced.linear_solver = BaLinearSolver::kIterativeSchur;
  LinearSolverChooser forced_chooser(forced);
  EXPECT_EQ(forced_chooser.Next(50, false), BaLinearSolver::kIterativeSchur);
  EXPECT_EQ(forced_chooser.Next(500, true), BaLinearSolver::kIterativeSchur);
}

// The room model's figures (docs/benchmarks.md): at 300 free images one
// iteration took 1.05 s with SPARSE_SCHUR and 0.71 s with ITERATIVE_SCHUR
// (265k observations); at 610 images (548k) 5.01 s and 1.42 s.
TEST(LinearSolverChooserTest, MeasuresHowEachSolverGrowsWithTheReconstruction) {
  LinearSolverChooser chooser(AutoOptions());
  EXPECT_EQ(chooser.Next(300, false), BaLinearSolver::kSparseSchur);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 10 * 1.05, 10, 265000), 300);
  EXPECT_EQ(chooser.Next(300, false), BaLinearSolver::kIterativeSchur);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 10 * 0.71, 10, 265000), 300);
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), 0.0);

  // One size measured: both predicted flat per observation. ITERATIVE_SCHUR
  // is 1.5 times cheaper, so it is chosen and SPARSE_SCHUR probed every
  // kProbePeriod-th time.
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 610), 1.05 / 265000, 1e-12);
  int num_sparse = 0;
  for (int i = 0; i < LinearSolverChooser::kProbePeriod; ++i) {
    num_sparse += chooser.Next(610, false) == BaLinearSolver::kSparseSchur ? 1 : 0;
  }
  EXPECT_EQ(num_sparse, 1);

  // The probe at 610 images and an ITERATIVE_SCHUR adjustment there.
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 10 * 5.01, 10, 548000), 610);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 10 * 1.42, 10, 548000), 610);
  const double expected_exponent =
      std::log((5.01 / 548000) / (1.05 / 265000)) / std::log(610.0 / 300.0);
  EXPECT_NEAR(expected_exponent, 1.18, 0.01);
  EXPECT_NEAR(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), expected_exponent, 1e-9);
  // ITERATIVE_SCHUR got slightly cheaper per observation: clamped to 0.
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kIterativeSchur), 0.0);
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 700),
              5.01 / 548000 * std::pow(700.0 / 610.0, expected_exponent), 1e-12);

  // SPARSE_SCHUR is now predicted more than twice as slow: never probed.
  for (int i = 0; i < 2 * LinearSolverChooser::kProbePeriod; ++i) {
    EXPECT_EQ(chooser.Next(700, false), BaLinearSolver::kIterativeSchur) << i;
  }
}

// A corridor-like scene: SPARSE_SCHUR's cost per observation stays flat, so
// it stays the choice as the reconstruction grows.
TEST(LinearSolverChooserTest, KeepsSparseSchurWhenItDoesNotGrow) {
  LinearSolverChooser chooser(AutoOptions());
  chooser.Next(150, false);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.0, 1, 100000), 150);
  chooser.Next(200, false);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 2.0, 1, 130000), 200);
  EXPECT_EQ(chooser.Next(250, false), BaLinearSolver::kSparseSchur);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.62, 1, 160000), 250);
  EXPECT_NEAR(chooser.GrowthExponent(BaLinearSolver::kSparseSchur),
              std::log((1.62 / 160000) / (1.0 / 100000)) / std::log(250.0 / 150.0), 1e-9);
  EXPECT_LT(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 600),
            0.8 * *chooser.PredictedCost(BaLinearSolver::kIterativeSchur, 600));
  EXPECT_EQ(chooser.Next(600, true), BaLinearSolver::kSparseSchur);
}

TEST(LinearSolverChooserTest, ProbesTheOtherSolverWhenClose) {
  LinearSolverChooser chooser(AutoOptions());
  chooser.Next(200, false);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.0, 1, 100000), 200);
  chooser.Next(200, false);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 1.2, 1, 100000), 200);
  // At 200 images SPARSE_SCHUR is 1.2 times cheaper: chosen, and
  // ITERATIVE_SCHUR tried every kProbePeriod-th time, never in the final BA.
  int num_iterative = 0;
  for (int i = 0; i < 4 * LinearSolverChooser::kProbePeriod; ++i) {
    num_iterative += chooser.Next(200, false) == BaLinearSolver::kIterativeSchur ? 1 : 0;
  }
  EXPECT_EQ(num_iterative, 4);
  for (int i = 0; i < 2 * LinearSolverChooser::kProbePeriod; ++i) {
    EXPECT_EQ(chooser.Next(200, true), BaLinearSolver::kSparseSchur);
  }
  // SPARSE_SCHUR measured at 300 images 1.5 times costlier per observation
  // (exponent 1): from there on ITERATIVE_SCHUR is predicted cheaper.
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.5, 1, 100000), 300);
  EXPECT_NEAR(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), 1.0, 1e-9);
  EXPECT_EQ(chooser.Next(300, true), BaLinearSolver::kIterativeSchur);
}

}  // namespace
}  // namespace viosfm

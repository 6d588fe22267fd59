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

  // One size measured: SPARSE_SCHUR extrapolated with the prior exponent,
  // ITERATIVE_SCHUR flat per observation.
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kSparseSchur),
            LinearSolverChooser::kPriorSparseExponent);
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kIterativeSchur), 0.0);
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 610),
              1.05 / 265000 * 610.0 / 300.0, 1e-12);
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kIterativeSchur, 610), 0.71 / 265000, 1e-12);

  // Both measured at 610 images.
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 10 * 5.01, 10, 548000), 610);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 10 * 1.42, 10, 548000), 610);
  // The room's SPARSE_SCHUR cost per observation grew as n^1.18 from 300 to 610 images.
  const double expected_exponent =
      std::log((5.01 / 548000) / (1.05 / 265000)) / std::log(610.0 / 300.0);
  EXPECT_NEAR(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), expected_exponent, 1e-9);
  // ITERATIVE_SCHUR got slightly cheaper per observation: clamped to 0.
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kIterativeSchur), 0.0);
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 700),
              5.01 / 548000 * std::pow(700.0 / 610.0, expected_exponent), 1e-12);

  // SPARSE_SCHUR is predicted more than twice as slow: never probed.
  for (int i = 0; i < 2 * LinearSolverChooser::kProbePeriod; ++i) {
    EXPECT_EQ(chooser.Next(700, false), BaLinearSolver::kIterativeSchur) << i;
  }
}

// A windowed run measures at one size only; its final BA over many more
// images does not extrapolate SPARSE_SCHUR as flat.
TEST(LinearSolverChooserTest, FinalAdjustmentFarBeyondTheMeasuredSize) {
  LinearSolverChooser chooser(AutoOptions());
  // SPARSE_SCHUR measured flat between 150 and 200 free images (exponent
  // 0), 5 us per observation; ITERATIVE_SCHUR 7.5 us.
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 0.75, 1, 150000), 150);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.0, 1, 200000), 200);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 1.5, 1, 200000), 200);
  EXPECT_EQ(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), 0.0);
  EXPECT_EQ(chooser.Next(200, true), BaLinearSolver::kSparseSchur);
  // Up to twice the largest measured size the measured exponent holds...
  EXPECT_EQ(chooser.Next(390, true), BaLinearSolver::kSparseSchur);
  // ...beyond it SPARSE_SCHUR grows at least with the prior exponent: a
  // windowed run's final BA over 2400 images.
  EXPECT_NEAR(*chooser.PredictedCost(BaLinearSolver::kSparseSchur, 2400), 5e-6 * 12.0, 1e-12);
  EXPECT_EQ(chooser.Next(2400, true), BaLinearSolver::kIterativeSchur);
}

// A corridor-like scene: SPARSE_SCHUR's cost per observation stays flat.
// The prior exponent first favours ITERATIVE_SCHUR; a probe measures
// SPARSE_SCHUR at a larger size, and from then on it is the choice.
TEST(LinearSolverChooserTest, KeepsSparseSchurWhenItDoesNotGrow) {
  LinearSolverChooser chooser(AutoOptions());
  chooser.Next(150, false);
  chooser.Record(Measured(BaLinearSolver::kSparseSchur, 1.0, 1, 100000), 150);  // 10 us
  chooser.Next(200, false);
  chooser.Record(Measured(BaLinearSolver::kIterativeSchur, 2.0, 1, 130000), 200);  // 15.4 us
  size_t num_images = 250;
  int num_sparse = 0;
  for (int i = 0; i < LinearSolverChooser::kProbePeriod; ++i, num_images += 50) {
    const BaLinearSolver solver = chooser.Next(num_images, false);
    const bool sparse = solver == BaLinearSolver::kSparseSchur;
    num_sparse += sparse ? 1 : 0;
    const double observations = 500.0 * static_cast<double>(num_images);
    chooser.Record(Measured(solver, (sparse ? 10e-6 : 15.4e-6) * observations, 1,
                            static_cast<int>(observations)),
                   num_images);
  }
  EXPECT_EQ(num_sparse, 1);  // the probe
  EXPECT_NEAR(chooser.GrowthExponent(BaLinearSolver::kSparseSchur), 0.0, 1e-9);
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

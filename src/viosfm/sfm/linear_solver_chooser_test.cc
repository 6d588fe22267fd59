#include "viosfm/sfm/linear_solver_chooser.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace viosfm {
namespace {

BundleAdjustmentOptions AutoOptions() {
  BundleAdjustmentOptions options;
  options.linear_solver = BaLinearSolver::kAuto;
  options.max_images_for_sparse_schur = 100;
  return options;
}

// n free images, `observations` in all, observations / `track_length`
// points, E covisible pairs.
BaProblemStructure Structure(size_t n, size_t observations, double track_length, size_t pairs) {
  BaProblemStructure structure;
  structure.num_free_images = n;
  structure.num_observations = observations;
  structure.num_points = static_cast<size_t>(std::lround(observations / track_length));
  structure.num_covisible_pairs = pairs;
  return structure;
}

// What the batched mapper records after an adjustment.
BundleAdjustmentSummary Summary(size_t observations, size_t points, double time_s) {
  BundleAdjustmentSummary summary;
  summary.num_observations = static_cast<int>(observations);
  summary.num_points = static_cast<int>(points);
  summary.num_iterations = 10;
  summary.time_s = time_s;
  summary.linear_solver = BaLinearSolver::kSparseSchur;
  return summary;
}

TEST(LinearSolverChooserTest, ForcedSolversAndSmallProblems) {
  BundleAdjustmentOptions forced = AutoOptions();
  forced.linear_solver = BaLinearSolver::kIterativeSchur;
  LinearSolverChooser forced_chooser(forced);
  EXPECT_EQ(forced_chooser.Next(50, false), BaLinearSolver::kIterativeSchur);
  EXPECT_EQ(forced_chooser.Next(Structure(500, 400000, 8.0, 1000), true),
            BaLinearSolver::kIterativeSchur);

  const LinearSolverChooser chooser(AutoOptions());
  // Up to max_images_for_sparse_schur, SPARSE_SCHUR whatever the structure.
  EXPECT_EQ(chooser.Next(Structure(100, 90000, 14.0, 100 * 99 / 2), false),
            BaLinearSolver::kSparseSchur);
}

// The suite's room and corridor at 610 images (docs/benchmarks.md): about
// as full a reduced camera matrix (E a half and a quarter of all pairs), but
// tracks of 13.7 and 8.7 observations. The room takes ITERATIVE_SCHUR (its
// mapping: 126 CPU-s against 225 with SPARSE_SCHUR), the corridor
// SPARSE_SCHUR (95 against 251).
TEST(LinearSolverChooserTest, RoomTakesIterativeSchurCorridorSparseSchur) {
  const LinearSolverChooser chooser(AutoOptions());
  const BaProblemStructure room = Structure(609, 547484, 13.8, 88162);
  const BaProblemStructure corridor = Structure(609, 457266, 8.83, 51462);
  EXPECT_NEAR(room.FillPerObservation(), 23.3, 0.05);
  EXPECT_NEAR(corridor.FillPerObservation(), 9.51, 0.05);
  for (const bool final : {false, true}) {
    EXPECT_EQ(chooser.Next(room, final), BaLinearSolver::kIterativeSchur);
    EXPECT_EQ(chooser.Next(corridor, final), BaLinearSolver::kSparseSchur);
  }
  // Short tracks but a reduced camera matrix whose factor is large (every
  // camera sharing points with every other at 2000 images): ITERATIVE_SCHUR.
  const BaProblemStructure dense_short = Structure(2000, 1600000, 8.0, 2000 * 1999 / 2);
  EXPECT_GT(dense_short.FillPerObservation(), LinearSolverChooser::kMaxFillPerObservation);
  EXPECT_EQ(chooser.Next(dense_short, true), BaLinearSolver::kIterativeSchur);
}

// The final adjustments of 100 s walks at 10 Hz (linear_solver_chooser.h):
// long tracks everywhere, but only the room's factor fills in; and the
// room at 500 and 2000 features per image, whose factorisation is the same
// (its work per observation is not), and the real handheld recording.
TEST(LinearSolverChooserTest, FinalAdjustmentByFactorizationWork) {
  const LinearSolverChooser chooser(AutoOptions());
  // The work per observation as the runs logged it.
  const auto with_work = [](BaProblemStructure structure, double per_observation) {
    structure.factorization_block_flops =
        per_observation * static_cast<double>(structure.num_observations);
    return structure;
  };
  const BaProblemStructure two_floors = with_work(Structure(979, 774296, 14.4, 71000), 10.2157);
  const BaProblemStructure corridor = with_work(Structure(980, 732499, 12.1, 129000), 148.832);
  const BaProblemStructure room = with_work(Structure(980, 873360, 17.5, 235000), 327.373);
  const BaProblemStructure room_500 = with_work(Structure(980, 432799, 16.8, 235000), 654.335);
  const BaProblemStructure room_2000 = with_work(Structure(980, 1732185, 17.3, 235000), 165.915);
  const BaProblemStructure handheld = with_work(Structure(299, 68930, 9.9, 20000), 43.1076);
  EXPECT_NEAR(room.FactorizationPerImage(), 2.92e5, 0.01e5);
  EXPECT_NEAR(room_2000.FactorizationPerImage(), room.FactorizationPerImage(),
              0.01 * room.FactorizationPerImage());
  EXPECT_NEAR(corridor.FactorizationPerImage(), 1.11e5, 0.01e5);
  EXPECT_EQ(chooser.Next(two_floors, true), BaLinearSolver::kSparseSchur);
  EXPECT_EQ(chooser.Next(corridor, true), BaLinearSolver::kSparseSchur);
  EXPECT_EQ(chooser.Next(handheld, true), BaLinearSolver::kSparseSchur);
  for (const BaProblemStructure& scene : {room, room_500, room_2000}) {
    EXPECT_EQ(chooser.Next(scene, true), BaLinearSolver::kIterativeSchur);
  }
  // Not the final one, or without the factorisation's work: the track length.
  for (const BaProblemStructure& scene : {two_floors, corridor, room}) {
    EXPECT_EQ(chooser.Next(scene, false), BaLinearSolver::kIterativeSchur);
    BaProblemStructure unknown = scene;
    unknown.factorization_block_flops = 0.0;
    EXPECT_EQ(chooser.Next(unknown, true), BaLinearSolver::kIterativeSchur);
  }
  // At the threshold SPARSE_SCHUR, just above it ITERATIVE_SCHUR; small
  // problems and forced solvers as ever.
  BaProblemStructure at = room;
  at.factorization_block_flops = LinearSolverChooser::kMaxFactorizationPerImageForFinalSparse *
                                 static_cast<double>(at.num_free_images);
  EXPECT_EQ(chooser.Next(at, true), BaLinearSolver::kSparseSchur);
  at.factorization_block_flops *= 1.001;
  EXPECT_EQ(chooser.Next(at, true), BaLinearSolver::kIterativeSchur);
  EXPECT_EQ(chooser.Next(with_work(Structure(100, 90000, 14.0, 4950), 5e5), true),
            BaLinearSolver::kSparseSchur);
  BundleAdjustmentOptions forced = AutoOptions();
  forced.linear_solver = BaLinearSolver::kIterativeSchur;
  EXPECT_EQ(LinearSolverChooser(forced).Next(two_floors, true), BaLinearSolver::kIterativeSchur);
}

TEST(LinearSolverChooserTest, Thresholds) {
  const LinearSolverChooser chooser(AutoOptions());
  // L at the threshold takes ITERATIVE_SCHUR, just below it SPARSE_SCHUR.
  BaProblemStructure at = Structure(300, 270000, 9.0, 1000);
  EXPECT_EQ(at.num_points, 30000u);
  EXPECT_EQ(chooser.Next(at, false), BaLinearSolver::kIterativeSchur);
  ++at.num_points;  // L = 8.9997
  EXPECT_EQ(chooser.Next(at, false), BaLinearSolver::kSparseSchur);
  // X at the threshold is still SPARSE_SCHUR, one covisible pair more is not.
  BaProblemStructure fill = Structure(400, 400000, 8.0, 0);
  fill.num_covisible_pairs = static_cast<size_t>(
      std::sqrt(LinearSolverChooser::kMaxFillPerObservation * 400.0 * 400000.0));
  while (fill.FillPerObservation() > LinearSolverChooser::kMaxFillPerObservation) {
    --fill.num_covisible_pairs;
  }
  EXPECT_EQ(chooser.Next(fill, false), BaLinearSolver::kSparseSchur);
  ++fill.num_covisible_pairs;
  EXPECT_EQ(chooser.Next(fill, false), BaLinearSolver::kIterativeSchur);
}

// The batched mapper's call: the size, and the track length of the previous
// adjustment (Record). Before any record: SPARSE_SCHUR.
TEST(LinearSolverChooserTest, SizeOnlyUsesTheRecordedTrackLength) {
  LinearSolverChooser chooser(AutoOptions());
  EXPECT_FALSE(chooser.RecordedTrackLength().has_value());
  EXPECT_EQ(chooser.Next(610, false), BaLinearSolver::kSparseSchur);
  chooser.Record(Summary(134040, 14206, 1.0), 149);  // the room at 150 images: L 9.4
  EXPECT_NEAR(*chooser.RecordedTrackLength(), 9.44, 0.01);
  EXPECT_EQ(chooser.Next(100, false), BaLinearSolver::kSparseSchur);
  EXPECT_EQ(chooser.Next(200, false), BaLinearSolver::kIterativeSchur);
  chooser.Record(Summary(457266, 51801, 1.0), 609);  // the corridor at 610: L 8.8
  EXPECT_EQ(chooser.Next(610, true), BaLinearSolver::kSparseSchur);
  chooser.Record(Summary(0, 0, 1.0), 0);  // nothing adjusted: the last L stays
  EXPECT_NEAR(*chooser.RecordedTrackLength(), 8.83, 0.01);
}

// Determinism: the choice is a function of the problems only. The old
// chooser measured wall time, so a loaded machine could change the solver
// and thereby the model; now the same sequence of problems gets the same
// solvers whatever the adjustments' times.
TEST(LinearSolverChooserTest, TheChoiceIgnoresTimings) {
  const std::vector<size_t> sizes = {50, 100, 150, 200, 300, 450, 610};
  const std::vector<double> lengths = {7.9, 8.7, 9.4, 8.2, 10.8, 8.1, 13.7};
  std::vector<std::vector<BaLinearSolver>> runs;
  for (const double time_s : {1e-3, 1.0, 1e3}) {  // a quiet, then a loaded machine
    LinearSolverChooser chooser(AutoOptions());
    std::vector<BaLinearSolver> solvers;
    for (size_t i = 0; i < sizes.size(); ++i) {
      solvers.push_back(chooser.Next(sizes[i], i + 1 == sizes.size()));
      const size_t observations = 900 * sizes[i];
      chooser.Record(
          Summary(observations, static_cast<size_t>(std::lround(observations / lengths[i])),
                  time_s * static_cast<double>(i + 1)),
          sizes[i]);
    }
    runs.push_back(solvers);
  }
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_EQ(runs[0], runs[2]);
  // And the choices follow the recorded track lengths.
  const std::vector<BaLinearSolver> expected = {
      BaLinearSolver::kSparseSchur,    BaLinearSolver::kSparseSchur,
      BaLinearSolver::kSparseSchur,  // L of the previous (100 images): 8.7
      BaLinearSolver::kIterativeSchur, BaLinearSolver::kSparseSchur,
      BaLinearSolver::kIterativeSchur, BaLinearSolver::kSparseSchur};
  EXPECT_EQ(runs[0], expected);
}

}  // namespace
}  // namespace viosfm

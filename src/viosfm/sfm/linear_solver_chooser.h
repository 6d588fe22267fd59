#pragma once

// The linear solver of the batched mapper's bundle adjustments: a
// deterministic function of the problem, so that the same input gives the
// same solver (and the same model) run after run, whatever the machine's
// load. (It used to be chosen from wall-clock timings of earlier
// adjustments, and a loaded machine changed the choice.)

#include <cstddef>
#include <optional>

#include "viosfm/ba/bundle_adjustment.h"
#include "viosfm/sfm/ba_problem_structure.h"

namespace viosfm {

// Neither SPARSE_SCHUR nor ITERATIVE_SCHUR is faster on every scene
// (bundle_adjustment.h). Measured once on the suite's room and corridor,
// 610 images each, mapping from the same stored matches, one thread
// (docs/benchmarks.md, "Bundle adjustment: choosing the linear solver"):
// the room's mapping took 225 CPU-s with SPARSE_SCHUR throughout and 126
// with ITERATIVE_SCHUR above 100 images; the corridor's 95 and 251. The
// scenes' reduced camera matrices are about as full (each camera shares
// points with a third to a half of the others; the corridor more at small
// sizes), so the fill does not tell them apart; the mean track length L
// (observations per point) does: 9.4 to 13.7 on the room from 150 images
// on (points stay in view of many cameras), 7.9 to 8.7 on the corridor
// (weak texture: short tracks), where the conjugate gradients with the
// Schur-Jacobi preconditioner needed about three times as long in the
// mapper's adjustments. And where the reduced camera matrix's Cholesky
// factor is large (X = E^2 / (n obs) of BaProblemStructure; SPARSE_SCHUR's
// cost per iteration and observation grew as 1.9 + 0.2 X us on the room),
// the factorisation dominates whatever the tracks. The rule:
//
//   n <= max_images_for_sparse_schur       SPARSE_SCHUR
//   L >= kMinTrackLengthForIterative       ITERATIVE_SCHUR
//   X > kMaxFillPerObservation             ITERATIVE_SCHUR   (with the structure)
//   otherwise                              SPARSE_SCHUR
//
// The final adjustment of a run (every image free, starting from the
// batches' adjusted poses) follows another rule, from the factorisation's
// work per free image F = BaProblemStructure::FactorizationPerImage (a
// symbolic factorisation under AMD; it tells a walk seen once, whose
// factor hardly fills in, from revisits, whose factor fills in, and it
// does not change with the features per image):
//
//   n <= max_images_for_sparse_schur       SPARSE_SCHUR
//   F <= kMaxFactorizationPerImageForFinalSparse   SPARSE_SCHUR
//   otherwise                              ITERATIVE_SCHUR
//
// Where the factor stays small the graph is a long chain of cameras, and
// there the conjugate gradients need many steps at every iteration. Measured
// on the final adjustment of 100 s simulated walks at 10 Hz (980 images,
// 2 threads, both solvers from the same batches; docs/benchmarks.md,
// "Real time"), at 1000 features per image: two_floors F = 8.1e3:
// SPARSE_SCHUR 75 s, ITERATIVE_SCHUR 371 s; corridor F = 1.11e5: 78 s and
// 157 s; room F = 2.92e5: 168 s and 28 s. The mean track length (14.4,
// 12.2, 17.6) would take ITERATIVE_SCHUR for all three. The rule used to
// divide the work by the observations instead of the images; the room
// at 2000 features then fell under it (166 per observation against 327 at
// 1000, the same factorisation) and took SPARSE_SCHUR for 385 s.
//
// A forced solver (options.linear_solver != kAuto) is always taken. Two scenes
// fixed the thresholds; a scene between them may get the slower solver, never
// a different result beyond the solvers' tolerance (both converge to the same
// cost: the trajectories of the table above agree to 0.1 mm).
class LinearSolverChooser {
 public:
  // Mean track length from which ITERATIVE_SCHUR is taken (observations per point).
  static constexpr double kMinTrackLengthForIterative = 9.0;
  // The largest X = E^2 / (n obs) at which SPARSE_SCHUR is taken.
  static constexpr double kMaxFillPerObservation = 20.0;
  // The largest F (block operations per free image) at which the final
  // adjustment takes SPARSE_SCHUR: between the corridor's 1.11e5 and the
  // room's 2.92e5 (above).
  static constexpr double kMaxFactorizationPerImageForFinalSparse = 1.8e5;

  explicit LinearSolverChooser(const BundleAdjustmentOptions& options);

  // The solver for an adjustment of the problem `structure`: the rule above
  // with the problem's own L and X. `final`: the last adjustment of the run,
  // decided by F when the structure has it (computed with_factorization),
  // else as the others.
  BaLinearSolver Next(const BaProblemStructure& structure, bool final) const;

  // The solver when only the number of free images is known: the rule above
  // with L of the last adjustment given to Record (its observations per
  // point), and without the fill test; SPARSE_SCHUR before any was recorded.
  BaLinearSolver Next(size_t num_free_images, bool final);

  // Keeps the track length of an adjustment (observations per point of its
  // summary; both are counts, so the choice stays deterministic) for the
  // size-only Next. Its time is not used.
  void Record(const BundleAdjustmentSummary& summary, size_t num_free_images);

  // L as the size-only Next sees it (none before a Record with points).
  std::optional<double> RecordedTrackLength() const { return recorded_track_length_; }

 private:
  BaLinearSolver Choose(size_t num_free_images, double mean_track_length,
                        std::optional<double> fill_per_observation) const;

  BundleAdjustmentOptions options_;
  std::optional<double> recorded_track_length_;
};

}  // namespace viosfm

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
// (bundle_adjustment.h): each costs about twice the other on one of the
// suite's room and corridor. Their reduced camera matrices are about as
// full, so the fill does not tell them apart; the mean track length L
// (observations per point) does: long where points stay in view of many
// cameras (a room), short where the texture is weak (a corridor), where the
// conjugate gradients with the Schur-Jacobi preconditioner need many more
// steps. And where the reduced camera matrix's Cholesky factor is large
// (X = E^2 / (n obs) of BaProblemStructure), the factorisation dominates
// whatever the tracks. See docs/benchmarks.md, section
// "Bundle adjustment: choosing the linear solver, deterministically". The rule:
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
// there the conjugate gradients need many steps at every iteration; the mean
// track length would take ITERATIVE_SCHUR for every 100 s simulated walk,
// where F separates the walk seen once from the room. The work is divided by
// the images, not the observations, so that the feature count does not move
// the choice. See docs/history/benchmarks-2026.md, section
// "Real time: where a 100 s recording's time goes".
//
// A forced solver (options.linear_solver != kAuto) is always taken. Two scenes
// fixed the thresholds; a scene between them may get the slower solver, never
// a different result beyond the solvers' tolerance (both converge to the same
// cost).
class LinearSolverChooser {
 public:
  // Mean track length from which ITERATIVE_SCHUR is taken (observations per point).
  static constexpr double kMinTrackLengthForIterative = 9.0;
  // The largest X = E^2 / (n obs) at which SPARSE_SCHUR is taken.
  static constexpr double kMaxFillPerObservation = 20.0;
  // The largest F (block operations per free image) at which the final
  // adjustment takes SPARSE_SCHUR: between the simulated corridor's and the
  // room's (above).
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

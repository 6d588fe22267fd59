#include "viosfm/sfm/linear_solver_chooser.h"

namespace viosfm {

LinearSolverChooser::LinearSolverChooser(const BundleAdjustmentOptions& options)
    : options_(options) {}

BaLinearSolver LinearSolverChooser::Choose(size_t num_free_images, double mean_track_length,
                                           std::optional<double> fill_per_observation) const {
  if (options_.linear_solver != BaLinearSolver::kAuto) return options_.linear_solver;
  if (num_free_images <= static_cast<size_t>(options_.max_images_for_sparse_schur)) {
    return BaLinearSolver::kSparseSchur;
  }
  if (mean_track_length >= kMinTrackLengthForIterative) return BaLinearSolver::kIterativeSchur;
  if (fill_per_observation && *fill_per_observation > kMaxFillPerObservation) {
    return BaLinearSolver::kIterativeSchur;
  }
  return BaLinearSolver::kSparseSchur;
}

BaLinearSolver LinearSolverChooser::Next(const BaProblemStructure& structure, bool final) const {
  if (final && structure.factorization_block_flops > 0.0 &&
      options_.linear_solver == BaLinearSolver::kAuto &&
      structure.num_free_images > static_cast<size_t>(options_.max_images_for_sparse_schur)) {
    return structure.FactorizationPerImage() <= kMaxFactorizationPerImageForFinalSparse
               ? BaLinearSolver::kSparseSchur
               : BaLinearSolver::kIterativeSchur;
  }
  const double track_length = structure.num_points > 0
                                  ? static_cast<double>(structure.num_observations) /
                                        static_cast<double>(structure.num_points)
                                  : 0.0;
  return Choose(structure.num_free_images, track_length, structure.FillPerObservation());
}

BaLinearSolver LinearSolverChooser::Next(size_t num_free_images, bool /*final*/) {
  return Choose(num_free_images, recorded_track_length_.value_or(0.0), std::nullopt);
}

void LinearSolverChooser::Record(const BundleAdjustmentSummary& summary,
                                 size_t /*num_free_images*/) {
  if (summary.num_points > 0 && summary.num_observations > 0) {
    recorded_track_length_ =
        static_cast<double>(summary.num_observations) / static_cast<double>(summary.num_points);
  }
}

}  // namespace viosfm

#include "viosfm/sfm/linear_solver_chooser.h"

#include <algorithm>
#include <cmath>

namespace viosfm {

LinearSolverChooser::LinearSolverChooser(const BundleAdjustmentOptions& options)
    : options_(options) {}

const LinearSolverChooser::SolverModel& LinearSolverChooser::Model(BaLinearSolver solver) const {
  return solver == BaLinearSolver::kSparseSchur ? sparse_ : iterative_;
}

double LinearSolverChooser::GrowthExponent(BaLinearSolver solver) const {
  return Model(solver).exponent;
}

std::optional<double> LinearSolverChooser::PredictedCost(BaLinearSolver solver,
                                                         size_t num_free_images) const {
  const SolverModel& model = Model(solver);
  if (!model.last) return std::nullopt;
  const double n = static_cast<double>(num_free_images);
  double exponent = model.exponent;
  if (solver == BaLinearSolver::kSparseSchur &&
      n > kMaxExtrapolation * model.largest_num_free_images) {
    exponent = std::max(exponent, kPriorSparseExponent);
  }
  return model.last->cost * std::pow(n / model.last->num_free_images, exponent);
}

BaLinearSolver LinearSolverChooser::Next(size_t num_free_images, bool final) {
  if (options_.linear_solver != BaLinearSolver::kAuto) return options_.linear_solver;
  if (num_free_images <= static_cast<size_t>(options_.max_images_for_sparse_schur)) {
    return BaLinearSolver::kSparseSchur;
  }
  if (!sparse_.last) return BaLinearSolver::kSparseSchur;
  if (!iterative_.last) return BaLinearSolver::kIterativeSchur;
  const double sparse = *PredictedCost(BaLinearSolver::kSparseSchur, num_free_images);
  const double iterative = *PredictedCost(BaLinearSolver::kIterativeSchur, num_free_images);
  const bool sparse_better = sparse <= iterative;
  const bool close = std::max(sparse, iterative) < kProbeMaxRatio * std::min(sparse, iterative);
  const bool probe = !final && ++num_choices_ % kProbePeriod == 0 && close;
  return sparse_better != probe ? BaLinearSolver::kSparseSchur : BaLinearSolver::kIterativeSchur;
}

void LinearSolverChooser::Record(const BundleAdjustmentSummary& summary, size_t num_free_images) {
  // Only adjustments in the measured range count.
  if (num_free_images <= static_cast<size_t>(options_.max_images_for_sparse_schur)) return;
  if (summary.num_iterations < 1 || summary.num_observations < 1 || summary.time_s <= 0.0) return;
  if (summary.linear_solver != BaLinearSolver::kSparseSchur &&
      summary.linear_solver != BaLinearSolver::kIterativeSchur) {
    return;
  }
  SolverModel& model = summary.linear_solver == BaLinearSolver::kSparseSchur ? sparse_ : iterative_;
  const Measurement now{static_cast<double>(num_free_images),
                        summary.time_s / summary.num_iterations / summary.num_observations};
  // The reference is the latest measurement at least kMinSizeRatio smaller.
  if (model.last && now.num_free_images >= kMinSizeRatio * model.last->num_free_images) {
    model.reference = model.last;
  }
  model.last = now;
  model.largest_num_free_images = std::max(model.largest_num_free_images, now.num_free_images);
  if (model.reference && now.num_free_images >= kMinSizeRatio * model.reference->num_free_images) {
    const double exponent = std::log(now.cost / model.reference->cost) /
                            std::log(now.num_free_images / model.reference->num_free_images);
    model.exponent = std::clamp(exponent, 0.0, kMaxExponent);
  }
}

}  // namespace viosfm

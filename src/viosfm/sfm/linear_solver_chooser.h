#pragma once

// The linear solver of the batched mapper's bundle adjustments, chosen by
// measurement.

#include <cstddef>
#include <optional>

#include "viosfm/ba/bundle_adjustment.h"

namespace viosfm {

// For each bundle adjustment with more than max_images_for_sparse_schur free
// images, when the options leave the solver to kAuto: neither SPARSE_SCHUR
// nor ITERATIVE_SCHUR is faster on every scene (bundle_adjustment.h), so the
// mapper measures. The first such adjustment runs SPARSE_SCHUR, the second
// ITERATIVE_SCHUR; after that each uses the one predicted to be cheaper, and
// every kProbePeriod-th tries the other again if it was predicted less than
// kProbeMaxRatio times slower, since the balance shifts as the
// reconstruction grows.
//
// Measurements are taken at different sizes, so each solver's time per
// iteration and observation is modelled as c * n^e in the number n of free
// images, with e measured from that solver's last two measurements at sizes
// at least kMinSizeRatio apart (clamped to [0, kMaxExponent]). Until
// measured, e is kPriorSparseExponent for SPARSE_SCHUR and 0 for
// ITERATIVE_SCHUR: a windowed run (--ba-window) measures at one size only,
// and its final BA over every image must not extrapolate SPARSE_SCHUR's
// cost as flat (a 2400-image room, measured at 200 free images, spent more
// than 20 minutes in its final SPARSE_SCHUR adjustment before it was
// stopped). Guessing wrong the
// other way costs at most ITERATIVE_SCHUR's factor of about 2 on a sparse
// scene. For the same reason an exponent measured between small sizes
// (150 and 200 free images) is not trusted more than kMaxExtrapolation
// times beyond the largest measured size: there SPARSE_SCHUR's exponent is
// at least the prior. How it grows depends on the scene: on the suite's room, whose
// cameras all see each other, SPARSE_SCHUR's cost per observation went from
// 4.0 to 9.1 us between 300 and 610 images (e = 1.2: the reduced camera
// matrix fills in) while ITERATIVE_SCHUR's stayed at 2.6-2.7 us; along the
// corridor the reduced camera matrix stays banded. Without the exponent, a
// SPARSE_SCHUR measurement on the room from a smaller reconstruction looks
// cheaper than SPARSE_SCHUR would be now.
class LinearSolverChooser {
 public:
  static constexpr int kProbePeriod = 4;
  static constexpr double kProbeMaxRatio = 2.0;
  static constexpr double kMinSizeRatio = 1.25;
  static constexpr double kMaxExponent = 2.0;
  static constexpr double kPriorSparseExponent = 1.0;
  static constexpr double kMaxExtrapolation = 2.0;

  explicit LinearSolverChooser(const BundleAdjustmentOptions& options);

  // The solver for an adjustment of `num_free_images` free images; `final`:
  // the last adjustment of the run (never a probe).
  BaLinearSolver Next(size_t num_free_images, bool final);

  // Records the time of an adjustment chosen by Next; `num_free_images` as
  // given to Next (held images are not in Ceres' reduced camera system).
  void Record(const BundleAdjustmentSummary& summary, size_t num_free_images);

  // Predicted seconds per iteration and observation at `num_free_images`,
  // once `solver` has been measured.
  std::optional<double> PredictedCost(BaLinearSolver solver, size_t num_free_images) const;

  // The growth exponent e of `solver` (measured, or the prior above).
  double GrowthExponent(BaLinearSolver solver) const;

 private:
  struct Measurement {
    double num_free_images = 0.0;
    double cost = 0.0;  // seconds per iteration and observation
  };
  struct SolverModel {
    std::optional<Measurement> last;
    std::optional<Measurement> reference;  // an earlier one, for the exponent
    double exponent = 0.0;
    double largest_num_free_images = 0.0;  // of any measurement
  };
  const SolverModel& Model(BaLinearSolver solver) const;

  BundleAdjustmentOptions options_;
  SolverModel sparse_{std::nullopt, std::nullopt, kPriorSparseExponent, 0.0};
  SolverModel iterative_;
  int num_choices_ = 0;
};

}  // namespace viosfm

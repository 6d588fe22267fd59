// Generic RANSAC with adaptive trial count and optional local optimisation
// (LO-RANSAC: each new best model is re-fitted on its inliers with a
// non-minimal estimator until the support stops growing).
//
// An Estimator provides
//   using X_t = ...; using Y_t = ...; using M_t = ...;   // data and model types
//   static constexpr int kMinNumSamples = ...;           // minimal sample size
//   // Models fitted to x.size() >= kMinNumSamples correspondences (none if degenerate).
//   static std::vector<M_t> Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y);
//   // Squared residual of every correspondence under the model.
//   static void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y,
//                         const M_t& model, std::vector<double>* squared_residuals);
// and optionally
//   // Squared residual of one correspondence (the same as Residuals gives).
//   static double SquaredResidual(const X_t& x, const Y_t& y, const M_t& model);
// with which a model's scoring stops as soon as its cost exceeds the best
// model's (every term is >= 0, so it cannot win): the same report, sooner.
// The local estimator (default: the same) has the same interface and is called
// with all current inliers.
//
// A correspondence is an inlier when its residual is at most max_error. Models
// are ranked by the MSAC cost sum_i min(r_i^2, max_error^2) (lower is better),
// which, unlike the bare inlier count, prefers the more accurate of two
// models with similar support. All random choices come from
// RansacOptions::seed: the same seed and data give the same report.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"

namespace viosfm {

struct RansacOptions {
  // Largest residual of an inlier, in the unit of the estimator's residual
  // (its square root). Default 1; callers set it.
  double max_error = 1.0;
  // Probability that at least one sample is outlier-free before stopping
  // early, in (0, 1). Default 0.999.
  double confidence = 0.999;
  // Trials always run, then the adaptive count decides. Default 0.
  int min_num_trials = 0;
  // Upper bound on trials. Default 10000.
  int max_num_trials = 10000;
  // Re-fit each new best model on its inliers (LO-RANSAC). Default true.
  bool local_optimization = true;
  // Re-fits per new best model, stopping earlier when the support stops
  // growing. Default 10.
  int max_local_iterations = 10;
  // Seed of the sampler. Default kDefaultRandomSeed (0).
  uint64_t seed = kDefaultRandomSeed;

  std::string Validate() const;  // empty if valid, else names the bad field
  bool Check() const { return Validate().empty(); }
};

// Trials needed to draw one all-inlier sample of `sample_size` with
// probability `confidence` when num_inliers of num_samples are inliers
// (ignores the min/max bounds). 0 if every correspondence is an inlier,
// int max if none is.
int64_t RansacNumTrials(size_t num_inliers, size_t num_samples, int sample_size, double confidence);

template <typename Model>
struct RansacReport {
  bool success = false;  // a model with at least the minimal sample of inliers was found
  int num_trials = 0;
  size_t num_inliers = 0;
  std::vector<char> inlier_mask;  // one per correspondence
  Model model{};
};

template <typename Estimator, typename LocalEstimator = Estimator>
class Ransac {
 public:
  using X_t = typename Estimator::X_t;
  using Y_t = typename Estimator::Y_t;
  using M_t = typename Estimator::M_t;
  using Report = RansacReport<M_t>;

  explicit Ransac(const RansacOptions& options) : options_(options) {
    VIOSFM_CHECK(options_.Check()) << options_.Validate();
  }

  Report Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y) const {
    return Estimate(x, y, {});
  }
  // The same, with models known beforehand (e.g. a prediction from other
  // sensors) scored before the first sample: a good one is kept (and
  // locally optimised) and its support lowers the number of trials needed.
  Report Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y,
                  const std::vector<M_t>& initial_models) const;

 private:
  struct Support {
    size_t num_inliers = 0;
    double cost = std::numeric_limits<double>::infinity();  // MSAC
    bool BetterThan(const Support& other) const { return cost < other.cost; }
  };

  // The model's support. With Estimator::SquaredResidual, the scoring stops
  // once the cost exceeds bail_cost (the best model's): the support returned
  // then has that partial cost, above bail_cost, and a partial inlier count;
  // a model that could beat bail_cost is always scored whole.
  Support Evaluate(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                   std::vector<double>* residuals,
                   double bail_cost = std::numeric_limits<double>::infinity()) const {
    const double max_squared = options_.max_error * options_.max_error;
    Support support;
    support.cost = 0.0;
    const auto add = [&](double residual) {
      if (residual <= max_squared) {
        ++support.num_inliers;
        support.cost += residual;
      } else {
        support.cost += max_squared;
      }
    };
    if constexpr (requires(const X_t& a, const Y_t& b, const M_t& m) {
                    { Estimator::SquaredResidual(a, b, m) } -> std::convertible_to<double>;
                  }) {
      for (size_t i = 0; i < x.size(); ++i) {
        add(Estimator::SquaredResidual(x[i], y[i], model));
        if (support.cost > bail_cost) break;
      }
    } else {
      Estimator::Residuals(x, y, model, residuals);
      for (const double residual : *residuals) add(residual);
    }
    return support;
  }

  RansacOptions options_;
};

template <typename Estimator, typename LocalEstimator>
typename Ransac<Estimator, LocalEstimator>::Report Ransac<Estimator, LocalEstimator>::Estimate(
    const std::vector<X_t>& x, const std::vector<Y_t>& y,
    const std::vector<M_t>& initial_models) const {
  VIOSFM_CHECK_EQ(x.size(), y.size());
  Report report;
  const size_t num_samples = x.size();
  constexpr int kSampleSize = Estimator::kMinNumSamples;
  if (num_samples < static_cast<size_t>(kSampleSize)) return report;

  Random random(options_.seed);
  std::vector<size_t> indices(num_samples);
  std::iota(indices.begin(), indices.end(), size_t{0});
  std::vector<X_t> sample_x(kSampleSize);
  std::vector<Y_t> sample_y(kSampleSize);
  std::vector<double> residuals;
  const double max_squared = options_.max_error * options_.max_error;

  Support best_support;
  bool have_model = false;
  M_t best_model{};
  int64_t needed_trials = options_.max_num_trials;

  // Re-fits the best model on its inliers while that improves the support.
  const auto optimize_locally = [&]() {
    std::vector<X_t> inlier_x;
    std::vector<Y_t> inlier_y;
    for (int iteration = 0; iteration < options_.max_local_iterations; ++iteration) {
      Estimator::Residuals(x, y, best_model, &residuals);
      inlier_x.clear();
      inlier_y.clear();
      for (size_t i = 0; i < num_samples; ++i) {
        if (residuals[i] <= max_squared) {
          inlier_x.push_back(x[i]);
          inlier_y.push_back(y[i]);
        }
      }
      if (inlier_x.size() < static_cast<size_t>(LocalEstimator::kMinNumSamples)) return;
      bool improved = false;
      for (const M_t& model : LocalEstimator::Estimate(inlier_x, inlier_y)) {
        const Support support = Evaluate(x, y, model, &residuals, best_support.cost);
        if (support.BetterThan(best_support)) {
          best_support = support;
          best_model = model;
          improved = true;
        }
      }
      if (!improved) return;
    }
  };

  for (const M_t& model : initial_models) {
    const Support support = Evaluate(x, y, model, &residuals);
    if (support.num_inliers < static_cast<size_t>(kSampleSize)) continue;
    if (!have_model || support.BetterThan(best_support)) {
      have_model = true;
      best_support = support;
      best_model = model;
      if (options_.local_optimization) optimize_locally();
      needed_trials =
          RansacNumTrials(best_support.num_inliers, num_samples, kSampleSize, options_.confidence);
    }
  }

  int trial = 0;
  for (; trial < options_.max_num_trials; ++trial) {
    if (trial >= options_.min_num_trials && trial >= needed_trials) break;
    // Partial Fisher-Yates shuffle: the first kSampleSize indices are the sample.
    for (int k = 0; k < kSampleSize; ++k) {
      const size_t pick = static_cast<size_t>(random.UniformInt(k, num_samples - 1));
      std::swap(indices[k], indices[pick]);
      sample_x[k] = x[indices[k]];
      sample_y[k] = y[indices[k]];
    }
    bool improved = false;
    for (const M_t& model : Estimator::Estimate(sample_x, sample_y)) {
      const Support support =
          Evaluate(x, y, model, &residuals,
                   have_model ? best_support.cost : std::numeric_limits<double>::infinity());
      if (!have_model || support.BetterThan(best_support)) {
        have_model = true;
        best_support = support;
        best_model = model;
        improved = true;
      }
    }
    if (improved) {
      if (options_.local_optimization) optimize_locally();
      needed_trials =
          RansacNumTrials(best_support.num_inliers, num_samples, kSampleSize, options_.confidence);
    }
  }

  report.num_trials = trial;
  if (!have_model) return report;
  report.model = best_model;
  Estimator::Residuals(x, y, best_model, &residuals);
  report.inlier_mask.assign(num_samples, 0);
  for (size_t i = 0; i < num_samples; ++i) {
    if (residuals[i] <= max_squared) {
      report.inlier_mask[i] = 1;
      ++report.num_inliers;
    }
  }
  report.success = report.num_inliers >= static_cast<size_t>(kSampleSize);
  return report;
}

}  // namespace viosfm

#include "viosfm/estimators/ransac.h"

namespace viosfm {

std::string RansacOptions::Validate() const {
  if (!(max_error > 0.0) || !std::isfinite(max_error)) return "max_error must be > 0 and finite";
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must be in (0, 1)";
  if (min_num_trials < 0) return "min_num_trials must be >= 0";
  if (max_num_trials < 1) return "max_num_trials must be >= 1";
  if (min_num_trials > max_num_trials) return "min_num_trials must be <= max_num_trials";
  if (max_local_iterations < 0) return "max_local_iterations must be >= 0";
  return "";
}

int64_t RansacNumTrials(size_t num_inliers, size_t num_samples, int sample_size,
                        double confidence) {
  if (num_samples == 0 || num_inliers == 0) return std::numeric_limits<int64_t>::max();
  const double inlier_ratio = static_cast<double>(num_inliers) / static_cast<double>(num_samples);
  const double good_sample = std::pow(inlier_ratio, sample_size);
  if (good_sample >= 1.0) return 0;
  const double denominator = std::log1p(-good_sample);
  if (!(denominator < 0.0)) return std::numeric_limits<int64_t>::max();
  const double trials = std::ceil(std::log1p(-confidence) / denominator);
  if (!(trials < 9e18)) return std::numeric_limits<int64_t>::max();
  return static_cast<int64_t>(trials);
}

}  // namespace viosfm

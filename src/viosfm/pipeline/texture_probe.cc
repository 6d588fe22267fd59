#include "viosfm/pipeline/texture_probe.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/timer.h"

namespace viosfm {

bool SettledByTextureProbe(const std::string& key) {
  return key == "frame_selection.target_rate_hz" || key == "sift.max_num_features";
}

bool SettledByFeatureBudget(const std::string& key) {
  return key == "sift.max_num_features" || key == "sift.max_image_size";
}

std::string FeatureBudgetOptions::Validate() const {
  if (features_per_second < 0) return "features_per_second must be >= 0";
  if (max_image_size < 64) return "max_image_size must be at least 64";
  return "";
}

double ReconstructionRateHz(const Sequence& sequence, double target_rate_hz) {
  const size_t n = sequence.images.size();
  if (sequence.unordered) return 0.0;
  // A recording not yet long enough to time is taken at its target rate.
  if (n < 2) return std::max(0.0, target_rate_hz);
  const double span_s =
      NsToSeconds(sequence.images.back().timestamp_ns - sequence.images.front().timestamp_ns);
  if (!(span_s > 0.0)) return 0.0;
  const double camera_hz = static_cast<double>(n - 1) / span_s;
  return target_rate_hz > 0.0 ? std::min(target_rate_hz, camera_hz) : camera_hz;
}

std::string ApplyFeatureBudget(const FeatureBudgetOptions& budget, double rate_hz,
                               SiftOptions* sift) {
  if (budget.features_per_second <= 0 || !(rate_hz > 0.0)) return "";
  const double per_frame = budget.features_per_second / rate_hz;
  if (per_frame >= sift->max_num_features) return "";
  sift->max_num_features = std::max(1, static_cast<int>(std::lround(per_frame)));
  if (sift->max_image_size == 0 || sift->max_image_size > budget.max_image_size) {
    sift->max_image_size = budget.max_image_size;
  }
  std::ostringstream line;
  line << budget.features_per_second << " features a second at " << std::setprecision(3) << rate_hz
       << " frames a second: " << sift->max_num_features << " a frame, images up to "
       << sift->max_image_size << " px";
  return line.str();
}

std::string TextureProbeOptions::Validate() const {
  if (num_frames < 1) return "num_frames must be at least 1";
  if (max_num_features < 1) return "max_num_features must be at least 1";
  if (!(target_rate_hz > 0.0 && std::isfinite(target_rate_hz))) {
    return "target_rate_hz must be positive";
  }
  if (!(percentile >= 0.0 && percentile <= 1.0)) return "percentile must be in [0, 1]";
  if (!(min_fraction > 0.0 && min_fraction <= 1.0)) return "min_fraction must be in (0, 1]";
  return "";
}

std::string TextureProbeResult::ToString(const TextureProbeOptions& options) const {
  std::ostringstream text;
  if (!probed) return "not probed";
  const double needed = options.min_fraction * options.max_num_features;
  text << (textured ? "textured" : "not textured") << ": ";
  if (frames.size() < num_planned) {
    const auto num_short = std::count_if(num_keypoints.begin(), num_keypoints.end(),
                                         [&](int count) { return count < needed; });
    text << num_short << " of the first " << frames.size() << " of " << num_planned
         << " frames probed hold fewer than " << needed << " of " << options.max_num_features
         << " keypoints (at the " << static_cast<int>(std::lround(100.0 * options.percentile))
         << "th percentile of them " << deciding_count << ")";
  } else {
    text << deciding_count << " of " << options.max_num_features << " keypoints at the "
         << static_cast<int>(std::lround(100.0 * options.percentile)) << "th percentile of "
         << frames.size() << " frames (" << needed << " needed)";
  }
  return text.str();
}

TextureProbeResult ProbeTexture(const Sequence& sequence, const std::vector<size_t>& candidates,
                                const SiftOptions& sift, const TextureProbeOptions& options,
                                FrameCache* frame_cache) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw InputError("texture probe options: " + error);
  }
  TextureProbeResult result;
  if (!options.enable || candidates.empty()) return result;
  Timer timer;
  timer.Start();
  // Evenly spread: the middle of each of num_frames equal shares.
  const size_t count = std::min(candidates.size(), static_cast<size_t>(options.num_frames));
  result.num_planned = count;
  for (size_t k = 0; k < count; ++k) {
    const size_t at = (2 * k + 1) * candidates.size() / (2 * count);
    result.frames.push_back(candidates[at]);
  }
  SiftOptions probe_sift = sift;
  probe_sift.max_num_features = options.max_num_features;
  const size_t rank = std::min(
      count - 1, static_cast<size_t>(std::floor(options.percentile * static_cast<double>(count))));
  const double needed = options.min_fraction * options.max_num_features;
  // kChunk frames at a time, in order, whatever the thread count (so the
  // frames probed are the same on every run); done once more than `rank`
  // of them fall short, since the rank-th smallest of all can then only be
  // short too.
  constexpr size_t kChunk = 2;
  result.num_keypoints.assign(count, 0);
  size_t probed = 0;
  size_t num_short = 0;
  while (probed < count && num_short <= rank) {
    const size_t end = std::min(count, probed + kChunk);
    ParallelFor(static_cast<int64_t>(end - probed), sift.num_threads, [&](int64_t i, int) {
      const size_t k = probed + static_cast<size_t>(i);
      const std::filesystem::path& path = sequence.images[result.frames[k]].path;
      const std::shared_ptr<const GreyImage> image = frame_cache->Preload(path);
      result.num_keypoints[k] = static_cast<int>(ExtractSift(*image, probe_sift).keypoints.size());
    });
    for (size_t k = probed; k < end; ++k) num_short += result.num_keypoints[k] < needed ? 1 : 0;
    probed = end;
  }
  result.frames.resize(probed);
  result.num_keypoints.resize(probed);
  std::vector<int> sorted = result.num_keypoints;
  std::sort(sorted.begin(), sorted.end());
  result.deciding_count = sorted[std::min(rank, probed - 1)];
  result.textured = result.deciding_count >= needed;
  result.probed = true;
  result.seconds = timer.ElapsedSeconds();
  return result;
}

}  // namespace viosfm

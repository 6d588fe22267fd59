#include "viosfm/pipeline/texture_probe.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/parallel.h"
#include "viosfm/util/timer.h"

namespace viosfm {

bool SettledByTextureProbe(const std::string& key) {
  return key == "frame_selection.target_rate_hz" || key == "sift.max_num_features";
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
  text << (textured ? "textured" : "not textured") << ": " << deciding_count << " of "
       << options.max_num_features << " keypoints at the "
       << static_cast<int>(std::lround(100.0 * options.percentile)) << "th percentile of "
       << frames.size() << " frames (" << options.min_fraction * options.max_num_features
       << " needed)";
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
  for (size_t k = 0; k < count; ++k) {
    const size_t at = (2 * k + 1) * candidates.size() / (2 * count);
    result.frames.push_back(candidates[at]);
  }
  SiftOptions probe_sift = sift;
  probe_sift.max_num_features = options.max_num_features;
  result.num_keypoints.assign(count, 0);
  ParallelFor(static_cast<int64_t>(count), sift.num_threads, [&](int64_t k, int) {
    const std::filesystem::path& path = sequence.images[result.frames[k]].path;
    const std::shared_ptr<const GreyImage> image = frame_cache->Read(path, /*keep=*/true);
    result.num_keypoints[k] = static_cast<int>(ExtractSift(*image, probe_sift).keypoints.size());
  });
  std::vector<int> sorted = result.num_keypoints;
  std::sort(sorted.begin(), sorted.end());
  const size_t rank = std::min(
      count - 1, static_cast<size_t>(std::floor(options.percentile * static_cast<double>(count))));
  result.deciding_count = sorted[rank];
  result.textured = result.deciding_count >= options.min_fraction * options.max_num_features;
  result.probed = true;
  result.seconds = timer.ElapsedSeconds();
  return result;
}

}  // namespace viosfm

// Frames or features: how a real-time run spends its budget, decided from
// the images' texture.
//
// A run's time grows with the frames times the features a frame, and its
// accuracy with the observations of each point. A recording whose every
// frame holds far more SIFT keypoints than a real-time run keeps (1000) is
// better served by fewer frames with more features each: each point keeps
// as many observations, each better localised. Where some frames have few
// keypoints (a bare wall, a stairwell), fewer frames leave those places
// with fewer observations still, and the rate stays.
//
// The probe extracts SIFT, with the run's SIFT options but `max_num_features`
// as the cap, on `num_frames` frames spread evenly over the frames the run
// will select, and calls the recording textured when the `percentile`-th
// smallest keypoint count reaches `min_fraction` of the cap. It probes them
// in time order, two at a time, and stops as soon as more frames fall short
// than the percentile allows (the decision cannot change then), so a
// recording that is not textured costs a few frames. A textured
// recording is then taken at `target_rate_hz` with `max_num_features` a
// frame. The run's fingerprint (run_fingerprint.h) and options.json record
// the rate and the feature count the probe settled, so stored data made
// with another decision (by another version of the probe) are refused.
//
// A recording textured everywhere keeps its accuracy at a lower rate with
// more features, while one with weak texture in places loses it, so only
// the former is slowed down. See docs/history/benchmarks-2026.md, section
// "Real time: where a 100 s recording's time goes" ("Frames or features").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "viosfm/features/sift.h"
#include "viosfm/io/frame_cache.h"
#include "viosfm/scene/sequence.h"
#include "viosfm/util/option_fields.h"

namespace viosfm {

struct TextureProbeOptions {
  // Decide the rate and the feature count from the texture (`viosfm run`'s
  // real-time preset turns it on; --rate or --max-features given with it turn
  // it off). Default false: the rate and the feature count as set.
  bool enable = false;
  // Frames probed, evenly spread over the frames to select (>= 1). Default 24.
  int num_frames = 24;
  // The probe's cap of keypoints a frame, and a textured recording's feature
  // count (>= 1). Default 2500.
  int max_num_features = 2500;
  // Hz, a textured recording's frame rate (> 0). Default 4.
  double target_rate_hz = 4.0;
  // Which of the probed frames' keypoint counts decides, as a fraction of
  // them from the fewest (in [0, 1]; 0: the frame with the fewest). Default
  // 0.1.
  double percentile = 0.1;
  // Textured when that count is at least this fraction of max_num_features
  // (in (0, 1]). Default 0.9.
  double min_fraction = 0.9;

  std::string Validate() const;  // empty if valid, else names the bad field

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"enable", "decide the frame rate and the feature count from the texture",
           kShapesStoredData},
          self.enable);
    visit({"num_frames", "frames probed, spread over the frames to select", kShapesStoredData},
          self.num_frames);
    visit({"max_num_features", "the probe's keypoint cap and a textured recording's features",
           kShapesStoredData},
          self.max_num_features);
    visit({"target_rate_hz", "Hz, a textured recording's frame rate", kShapesStoredData},
          self.target_rate_hz);
    visit({"percentile", "the probed frame that decides, as a fraction from the fewest keypoints",
           kShapesStoredData},
          self.percentile);
    visit({"min_fraction", "textured when that frame's keypoints reach this fraction of the cap",
           kShapesStoredData},
          self.min_fraction);
  }
};

// A real-time run's budget of SIFT features a second of recording, spread
// over the frames it reconstructs: at a rate of r frames a second, each gets
// min(sift.max_num_features, features_per_second / r) features, found on
// images reduced to at most max_image_size pixels. A sequence whose frames
// come slower than features_per_second / sift.max_num_features (sparse
// keyframes, photos taken one by one) is not limited by it, nor is a photo
// collection without stamps: they have the time for every feature.
struct FeatureBudgetOptions {
  // Features a second of recording (>= 0; default 0: no budget).
  int features_per_second = 0;
  // px, the longest image side where the budget limits (>= 64; default 800).
  // SIFT starts from the image doubled, so a 1280x720 camera's frames cost
  // most of a core at 10 Hz; at a thousand features a frame the reduced
  // image holds the accuracy (docs/benchmarks.md, "Real time"). 752-pixel
  // cameras (EuRoC's) keep their full size.
  int max_image_size = 800;
  // Where the budget does not limit a timed recording (its frames come
  // slower than features_per_second / sift.max_num_features: sparse
  // keyframes), the run has the time for the paper's retrieval neighbours
  // and bundle-adjustment settings, and takes them
  // (pipeline_options.h ApplySparseRecordingSettings).
  bool paper_settings_when_sparse = true;

  std::string Validate() const;  // empty if valid, else names the bad field

  template <class Self, class Visitor>
  static void VisitFields(Self& self, Visitor&& visit) {
    visit({"features_per_second", "SIFT features a second of recording; 0: no budget",
           kShapesStoredData},
          self.features_per_second);
    visit(
        {"max_image_size", "px, the longest image side where the budget limits", kShapesStoredData},
        self.max_image_size);
    visit({"paper_settings_when_sparse",
           "where the budget does not limit (sparse frames): the paper's N2 and adjustment",
           kRunOnly},
          self.paper_settings_when_sparse);
  }
};

// Whether the option `key` is one a user's choice of takes the budget off:
// sift.max_num_features and sift.max_image_size.
bool SettledByFeatureBudget(const std::string& key);

// The frames a second a run reconstructs: the selection's target rate, or
// the camera's where that is slower or no target is set (0: every frame);
// the target rate for fewer than two images (a recording just begun); 0
// for a photo collection without stamps.
double ReconstructionRateHz(const Sequence& sequence, double target_rate_hz);

// Applies the budget at `rate_hz` to `sift`; returns a line saying what it
// did ("" when it does not limit).
std::string ApplyFeatureBudget(const FeatureBudgetOptions& budget, double rate_hz,
                               SiftOptions* sift);

// Whether the option `key` (options.json's key) is one the probe settles:
// frame_selection.target_rate_hz and sift.max_num_features.
bool SettledByTextureProbe(const std::string& key);

struct TextureProbeResult {
  bool probed = false;  // false: options.enable was false, or no frame to probe
  // Indices into the sequence's images of the frames probed (fewer than
  // num_frames when the probe stopped early) and their keypoint counts
  // under the probe's cap.
  std::vector<size_t> frames;
  std::vector<int> num_keypoints;
  size_t num_planned = 0;  // min(num_frames, candidates)
  // The percentile-th smallest count of the num_frames planned; when the
  // probe stopped early, that of the frames probed (short either way).
  int deciding_count = 0;
  bool textured = false;
  double seconds = 0.0;
  // "textured: 2500 of 2500 keypoints at the 10th percentile of 24 frames"
  std::string ToString(const TextureProbeOptions& options) const;
};

// Probes the images `candidates` (indices into sequence.images, in time
// order; the frames the run will select) as above, decoding each probed
// frame through `frame_cache`, which keeps it for the stages after. `sift` are the run's SIFT
// options (their max_num_features is replaced by the probe's). Throws
// InputError for invalid options or an unreadable image.
TextureProbeResult ProbeTexture(const Sequence& sequence, const std::vector<size_t>& candidates,
                                const SiftOptions& sift, const TextureProbeOptions& options,
                                FrameCache* frame_cache);

}  // namespace viosfm

// Stage 8 of a `viosfm run` (pipeline.h): each point's colour, the mean
// over its observations of the image value at the keypoint (grey images
// give grey). The values are sampled while the features are extracted
// (KeypointGreyValues), so no image is decoded for this; an image whose
// features an earlier run stored is decoded here (counted by the frame
// cache).
#pragma once

#include <mutex>
#include <unordered_map>
#include <vector>

#include "viosfm/io/frame_cache.h"
#include "viosfm/pipeline/stage_frames.h"
#include "viosfm/scene/features.h"
#include "viosfm/scene/reconstruction.h"
#include "viosfm/sfm/batched_mapper.h"

namespace viosfm {

// Each keypoint's grey value: the pixel nearest the keypoint (viosfm's
// convention: pixel (x, y) has its centre at (x, y)).
std::vector<uint8_t> SampleKeypointGreyValues(const GreyImage& pixels,
                                              const FeatureKeypoints& keypoints);

// SampleKeypointGreyValues by image.
class KeypointGreyValues {
 public:
  // Thread-safe.
  void Sample(image_t image_id, const GreyImage& pixels, const FeatureKeypoints& keypoints);
  // Values sampled before the image had its id (thread-safe).
  void Set(image_t image_id, std::vector<uint8_t> values);
  // The values of `image_id`, or null if it was not sampled.
  const std::vector<uint8_t>* Find(image_t image_id) const;

 private:
  mutable std::mutex mutex_;
  std::unordered_map<image_t, std::vector<uint8_t>> values_;
};

// input.images[i] is frames.sequence.images[i] (LoadMapperInputStage).
// Images without sampled values are taken from `frames`.
void ColorPointsStage(const SelectedFrames& frames, const BatchedMapperInput& input,
                      bool show_progress, KeypointGreyValues* values, FrameCache* frame_cache,
                      Reconstruction* reconstruction);

}  // namespace viosfm

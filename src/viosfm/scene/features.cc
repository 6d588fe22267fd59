#include "viosfm/scene/features.h"

#include <cmath>

namespace viosfm {

FeatureKeypoint FeatureKeypoint::FromScaleOrientation(float x, float y, float scale,
                                                      float orientation_rad) {
  FeatureKeypoint keypoint;
  keypoint.x = x;
  keypoint.y = y;
  const float c = std::cos(orientation_rad);
  const float s = std::sin(orientation_rad);
  keypoint.a11 = scale * c;
  keypoint.a12 = -scale * s;
  keypoint.a21 = scale * s;
  keypoint.a22 = scale * c;
  return keypoint;
}

float FeatureKeypoint::Scale() const {
  return 0.5f * (std::sqrt(a11 * a11 + a21 * a21) + std::sqrt(a12 * a12 + a22 * a22));
}

float FeatureKeypoint::Orientation() const {
  return std::atan2(a21, a11);
}

image_pair_t ImagePairToPairId(image_t image_id1, image_t image_id2) {
  if (SwapImagePair(image_id1, image_id2)) std::swap(image_id1, image_id2);
  return kMaxNumImages * image_id1 + image_id2;
}

std::pair<image_t, image_t> PairIdToImagePair(image_pair_t pair_id) {
  const image_t image_id2 = static_cast<image_t>(pair_id % kMaxNumImages);
  const image_t image_id1 = static_cast<image_t>((pair_id - image_id2) / kMaxNumImages);
  return {image_id1, image_id2};
}

}  // namespace viosfm

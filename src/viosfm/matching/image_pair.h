// An unordered image pair in COLMAP's order: image_id1 < image_id2.
#pragma once

#include <compare>

#include "viosfm/util/types.h"

namespace viosfm {

struct ImagePair {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;

  // The pair of `a` and `b` in order (smaller id first).
  static ImagePair Ordered(image_t a, image_t b) {
    return a < b ? ImagePair{a, b} : ImagePair{b, a};
  }
  auto operator<=>(const ImagePair&) const = default;
};

}  // namespace viosfm

// An 8-bit single-channel image, row-major without padding: the pixel at
// column x, row y is pixels[y * width + x]. Pixel (0, 0) is the top-left one;
// its centre has image coordinates (0, 0) in the OpenCV convention.
#pragma once

#include <cstdint>
#include <vector>

namespace viosfm {

struct GreyImage {
  int width = 0;   // pixels
  int height = 0;  // pixels
  std::vector<uint8_t> pixels;

  GreyImage() = default;
  GreyImage(int width, int height, uint8_t value = 0)
      : width(width), height(height), pixels(static_cast<size_t>(width) * height, value) {}

  uint8_t& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
  uint8_t at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
  bool empty() const { return pixels.empty(); }
};

}  // namespace viosfm

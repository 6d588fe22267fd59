// Reading and writing 8-bit grey images (PNG output; any format OpenCV can
// decode for input).
#pragma once

#include <filesystem>

#include "viosfm/sensor/grey_image.h"

namespace viosfm {

// Writes `image` as an 8-bit grey PNG, atomically (to a temporary ".png"
// sibling, then renamed). Throws InputError naming `path` if it cannot be
// written, and InternalError if the image is empty or its pixel count does
// not match width * height.
void WriteGreyPng(const std::filesystem::path& path, const GreyImage& image);

// Reads an image file as 8-bit grey (colour images are converted). Throws
// InputError naming `path` if the file is missing or cannot be decoded.
GreyImage ReadGreyImage(const std::filesystem::path& path);

}  // namespace viosfm

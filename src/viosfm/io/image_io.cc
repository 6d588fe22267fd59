#include "viosfm/io/image_io.h"

#include <unistd.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "viosfm/io/image_header.h"
#include "viosfm/util/errors.h"

namespace viosfm {

void WriteGreyPng(const std::filesystem::path& path, const GreyImage& image) {
  VIOSFM_CHECK(image.width > 0 && image.height > 0) << "empty image for " << path.string();
  VIOSFM_CHECK_EQ(image.pixels.size(), static_cast<size_t>(image.width) * image.height);
  // OpenCV picks the encoder from the extension, so the temporary name ends
  // in ".png" whatever the final name is.
  std::filesystem::path temp = path;
  temp += ".tmp-" + std::to_string(::getpid()) + ".png";
  const cv::Mat mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()));
  bool written = false;
  try {
    written = cv::imwrite(temp.string(), mat);
  } catch (const cv::Exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw InputError(path.string(), 0, std::string("cannot write PNG: ") + e.what());
  }
  if (!written) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw InputError(path.string(), 0, "cannot write PNG (is the folder writable?)");
  }
  std::error_code error;
  std::filesystem::rename(temp, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw InputError(path.string(), 0, "cannot rename the temporary PNG: " + error.message());
  }
}

GreyImage ReadGreyImage(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw InputError(path.string(), 0, "image file not found (expected a PNG/JPEG file)");
  }
  // The size its header states, before the decoder allocates for it.
  if (const std::optional<ImageHeaderSize> size = ReadImageHeaderSize(path);
      size && size->width > kMaxImagePixels / size->height) {
    throw InputError(path.string(), 0,
                     "the image's header states " + std::to_string(size->width) + "x" +
                         std::to_string(size->height) + " pixels, more than the " +
                         std::to_string(kMaxImagePixels) + " an image may have");
  }
  cv::Mat mat;
  try {
    mat = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    throw InputError(path.string(), 0, std::string("cannot decode image: ") + e.what());
  }
  if (mat.empty() || mat.type() != CV_8UC1) {
    throw InputError(path.string(), 0, "cannot decode image (expected a PNG/JPEG file)");
  }
  GreyImage image(mat.cols, mat.rows);
  for (int y = 0; y < mat.rows; ++y) {
    const uint8_t* row = mat.ptr<uint8_t>(y);
    std::copy(row, row + mat.cols, image.pixels.begin() + static_cast<size_t>(y) * mat.cols);
  }
  return image;
}

}  // namespace viosfm

#include "viosfm/io/image_header.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "viosfm/io/image_io.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::InputErrorMessage;

// The header of a PNG of `width` x `height` (8-bit grey), without its data.
std::string PngHeader(uint32_t width, uint32_t height) {
  std::string bytes = "\x89PNG\r\n\x1a\n";
  bytes += std::string("\0\0\0\x0d", 4) + "IHDR";
  for (const uint32_t value : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8)
      bytes += static_cast<char>((value >> shift) & 0xff);
  }
  bytes += std::string("\x08\x00\x00\x00\x00", 5);
  return bytes;
}

TEST(ReadImageHeaderSize, EveryFormatOpenCvWritesGivesTheDecodedSize) {
  const fs::path folder = testing::MakeScratchFolder("image_header");
  const cv::Mat image(37, 61, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const char* extension : {".png", ".jpg", ".pgm", ".ppm", ".bmp"}) {
    const fs::path path = folder / (std::string("image") + extension);
    cv::Mat written = image;
    if (std::string(extension) == ".pgm") cv::cvtColor(image, written, cv::COLOR_BGR2GRAY);
    ASSERT_TRUE(cv::imwrite(path.string(), written)) << extension;
    const std::optional<ImageHeaderSize> size = ReadImageHeaderSize(path);
    ASSERT_TRUE(size.has_value()) << extension;
    EXPECT_EQ(size->width, 61) << extension;
    EXPECT_EQ(size->height, 37) << extension;
  }
  testing::WriteTextFile(folder / "text.pgm", "P2\n# a comment\n  640\n480 255\n0 0 0\n");
  EXPECT_EQ(ReadImageHeaderSize(folder / "text.pgm")->width, 640);
  testing::WriteTextFile(folder / "other.tif", "II*\0 not a format read here");
  EXPECT_FALSE(ReadImageHeaderSize(folder / "other.tif").has_value());
}

TEST(ReadImageHeaderSize, MalformedHeadersNameTheFile) {
  const fs::path folder = testing::MakeScratchFolder("image_header_bad");
  testing::WriteTextFile(folder / "short.png", PngHeader(10, 10).substr(0, 20));
  EXPECT_THAT(InputErrorMessage([&] { ReadImageHeaderSize(folder / "short.png"); }),
              HasSubstr("short.png: a PNG file without its IHDR header"));
  testing::WriteTextFile(folder / "zero.png", PngHeader(0, 10));
  EXPECT_THAT(InputErrorMessage([&] { ReadImageHeaderSize(folder / "zero.png"); }),
              HasSubstr("states a size of 0x10 pixels"));
  testing::WriteTextFile(folder / "nosof.jpg", std::string("\xff\xd8\xff\xd9", 4));
  EXPECT_THAT(InputErrorMessage([&] { ReadImageHeaderSize(folder / "nosof.jpg"); }),
              HasSubstr("without a frame header"));
}

TEST(ReadGreyImage, AHugeDeclaredSizeIsRefusedBeforeDecoding) {
  const fs::path folder = testing::MakeScratchFolder("image_huge");
  // A 32000 x 32000 PNG header with a few bytes of data: decoding it would
  // allocate 1 GB before finding the data short.
  testing::WriteTextFile(folder / "huge.png", PngHeader(32000, 32000) + std::string(64, '\0'));
  EXPECT_THAT(InputErrorMessage([&] { ReadGreyImage(folder / "huge.png"); }),
              HasSubstr("huge.png: the image's header states 32000x32000 pixels"));
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/image_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;

GreyImage MakePattern(int width, int height) {
  GreyImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) image.at(x, y) = static_cast<uint8_t>((x * 7 + y * 13) % 256);
  }
  return image;
}

TEST(ImageIo, WriteThenReadGivesIdenticalPixels) {
  const auto folder = testing::MakeScratchFolder("image_io_roundtrip");
  const auto path = folder / "frame.png";
  const GreyImage image = MakePattern(37, 23);
  WriteGreyPng(path, image);
  const GreyImage read = ReadGreyImage(path);
  EXPECT_EQ(read.width, 37);
  EXPECT_EQ(read.height, 23);
  EXPECT_EQ(read.pixels, image.pixels);
  // No temporary file is left next to the output.
  int num_files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(folder))
    ++num_files;
  EXPECT_EQ(num_files, 1);
}

TEST(ImageIo, OverwritesAnExistingFile) {
  const auto path = testing::MakeScratchFolder("image_io_overwrite") / "a.png";
  WriteGreyPng(path, GreyImage(4, 3, 10));
  WriteGreyPng(path, MakePattern(5, 6));
  EXPECT_EQ(ReadGreyImage(path).pixels, MakePattern(5, 6).pixels);
}

TEST(ImageIo, MissingFileNamesThePath) {
  const auto path = testing::MakeScratchFolder("image_io_missing") / "nothing.png";
  try {
    ReadGreyImage(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path.string()));
    EXPECT_EQ(e.path(), path.string());
  }
}

TEST(ImageIo, GarbageBytesNameThePath) {
  const auto path = testing::MakeScratchFolder("image_io_garbage") / "broken.png";
  {
    std::ofstream stream(path, std::ios::binary);
    stream << "this is not an image at all \x01\x02\x03";
  }
  try {
    ReadGreyImage(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path.string()));
    EXPECT_THAT(e.what(), HasSubstr("decode"));
  }
}

TEST(ImageIo, UnwritableFolderNamesThePath) {
  const auto path = testing::MakeScratchFolder("image_io_unwritable") / "no_such_dir" / "x.png";
  EXPECT_THROW(WriteGreyPng(path, GreyImage(2, 2)), InputError);
}

}  // namespace
}  // namespace viosfm

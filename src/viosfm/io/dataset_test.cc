#include "viosfm/io/dataset.h"

#include <gtest/gtest.h>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

bool Contains(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

// An image folder given two cameras names the folder and the options that
// give its camera, each as the command line spells it.
TEST(ReadDataset, ImageFolderWithTwoCamerasNamesTheCameraOptions) {
  const fs::path folder = testing::MakeScratchFolder("dataset_two_cameras");
  DatasetReadOptions options;
  options.image_folder.camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240});
  options.image_folder.camera_yaml = folder / "sensor.yaml";
  const InputError error = testing::ExpectInputError([&] { ReadDataset(folder, options); });
  const std::string message = error.what();
  EXPECT_TRUE(Contains(message, folder.string())) << message;
  EXPECT_TRUE(Contains(message, "read as an image folder")) << message;
  EXPECT_TRUE(Contains(message, "--camera-yaml FILE")) << message;
  EXPECT_TRUE(Contains(message, "--calibration FILE")) << message;
  EXPECT_TRUE(Contains(message, "`viosfm features` also takes --camera MODEL")) << message;
}

TEST(ReadDataset, MissingFolderIsNamed) {
  const fs::path folder = testing::MakeScratchFolder("dataset_missing") / "absent";
  const InputError error =
      testing::ExpectInputError([&] { ReadDataset(folder, DatasetReadOptions{}); });
  EXPECT_TRUE(Contains(error.what(), "dataset folder not found")) << error.what();
  EXPECT_TRUE(Contains(error.what(), folder.string())) << error.what();
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/image_folder.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using ::testing::HasSubstr;
using testing::InputErrorMessage;
using testing::WriteTextFile;

ImageFolderOptions PinholeOptions() {
  Camera camera;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = 64;
  camera.height = 48;
  camera.params = {50.0, 51.0, 32.0, 24.0};
  ImageFolderOptions options;
  options.camera = camera;
  return options;
}

TEST(ReadImageFolder, StampsFromFileNames) {
  const fs::path folder = testing::MakeScratchFolder("images_by_name");
  for (const char* name : {"1000000300.png", "1000000100.jpg", "1000000200.JPEG", "notes.txt"}) {
    WriteTextFile(folder / name, "x");
  }
  fs::create_directory(folder / "sub");
  WriteTextFile(folder / "sub" / "frame.png", "x");  // sub-folders are not searched

  const Sequence sequence = ReadImageFolder(folder, PinholeOptions());
  EXPECT_EQ(sequence.root, folder);
  ASSERT_EQ(sequence.images.size(), 3u);
  EXPECT_FALSE(sequence.unordered);
  EXPECT_EQ(sequence.images[0].timestamp_ns, 1000000100);
  EXPECT_EQ(sequence.images[0].path, folder / "1000000100.jpg");
  EXPECT_EQ(sequence.images[1].timestamp_ns, 1000000200);
  EXPECT_EQ(sequence.images[1].path, folder / "1000000200.JPEG");
  EXPECT_EQ(sequence.images[2].timestamp_ns, 1000000300);
  EXPECT_EQ(sequence.images[2].path, folder / "1000000300.png");
  EXPECT_EQ(sequence.rig.camera.camera_id, 1u);
  EXPECT_EQ(sequence.rig.camera.model_id, CameraModelId::kPinhole);
  EXPECT_THAT(sequence.rig.camera.params, ::testing::ElementsAre(50.0, 51.0, 32.0, 24.0));
  EXPECT_FALSE(sequence.has_imu());
  EXPECT_FALSE(sequence.has_ground_truth());
}

TEST(ReadImageFolder, StampsFromTimestampsFile) {
  const fs::path folder = testing::MakeScratchFolder("images_with_stamps");
  for (const char* name : {"a.png", "b.png", "c.jpg", "unlisted.png"})
    WriteTextFile(folder / name, "x");
  const fs::path stamps = folder / "times.txt";
  WriteTextFile(stamps,
                "# filename timestamp\n"
                "b.png   1403715273.5\n"
                "a.png\t1403715273262142976\r\n"
                "\n"
                "c.jpg,12\n");
  ImageFolderOptions options = PinholeOptions();
  options.timestamps_file = stamps;
  const Sequence sequence = ReadImageFolder(folder, options);
  ASSERT_EQ(sequence.images.size(), 3u);
  EXPECT_EQ(sequence.images[0].timestamp_ns, 12);
  EXPECT_EQ(sequence.images[0].path, folder / "c.jpg");
  EXPECT_EQ(sequence.images[1].timestamp_ns, 1403715273262142976);
  EXPECT_EQ(sequence.images[1].path, folder / "a.png");
  EXPECT_EQ(sequence.images[2].timestamp_ns, 1403715273500000000);
  EXPECT_EQ(sequence.images[2].path, folder / "b.png");
}

TEST(ReadImageFolder, CameraFromSensorYaml) {
  const fs::path folder = testing::MakeScratchFolder("images_yaml");
  WriteTextFile(folder / "1000000005.png", "x");
  WriteTextFile(folder / "sensor.yaml",
                "%YAML:1.0\n"
                "T_BS:\n  cols: 4\n  rows: 4\n"
                "  data: [1, 0, 0, 0.1, 0, 1, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1]\n"
                "rate_hz: 15\nresolution: [640, 480]\ncamera_model: pinhole\n"
                "intrinsics: [500, 501, 320, 240]\n"
                "distortion_model: radial-tangential\n"
                "distortion_coefficients: [-0.1, 0.01, 0.001, 0.002]\n");
  ImageFolderOptions options;
  options.camera_yaml = folder / "sensor.yaml";
  const Sequence sequence = ReadImageFolder(folder, options);
  ASSERT_EQ(sequence.images.size(), 1u);
  EXPECT_EQ(sequence.images[0].timestamp_ns, 1000000005);
  EXPECT_EQ(sequence.rig.camera.model_id, CameraModelId::kOpenCV);
  EXPECT_THAT(sequence.rig.camera.params,
              ::testing::ElementsAre(500, 501, 320, 240, -0.1, 0.01, 0.001, 0.002));
  EXPECT_EQ(sequence.rig.body_from_cam.translation, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_DOUBLE_EQ(sequence.rig.camera_rate_hz, 15.0);
}

TEST(ReadImageFolder, PhotosWithoutStampsOrCalibration) {
  // Names that are no timestamps, or frame numbers: an unordered collection
  // in name order; no calibration: the camera guessed from the image size.
  const fs::path folder = testing::MakeScratchFolder("images_unordered");
  const GreyImage image(64, 48, 128);
  for (const char* name : {"IMG_0002.png", "0001.png", "IMG_0010.png"}) {
    WriteGreyPng(folder / name, image);
  }
  const Sequence sequence = ReadImageFolder(folder, ImageFolderOptions());
  EXPECT_TRUE(sequence.unordered);
  ASSERT_EQ(sequence.images.size(), 3u);
  EXPECT_EQ(sequence.images[0].path, folder / "0001.png");
  EXPECT_EQ(sequence.images[1].path, folder / "IMG_0002.png");
  EXPECT_EQ(sequence.images[2].path, folder / "IMG_0010.png");
  EXPECT_EQ(sequence.images[0].timestamp_ns, 1'000'000'000);
  EXPECT_EQ(sequence.images[2].timestamp_ns, 3'000'000'000);
  EXPECT_TRUE(sequence.camera_guessed);
  EXPECT_EQ(sequence.rig.camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(sequence.rig.camera.width, 64u);
  EXPECT_EQ(sequence.rig.camera.height, 48u);
  // COLMAP's guess: 1.2 times the larger side, the centre, no distortion.
  EXPECT_THAT(sequence.rig.camera.params,
              ::testing::ElementsAre(::testing::DoubleEq(76.8), ::testing::DoubleEq(31.5),
                                     ::testing::DoubleEq(23.5), ::testing::DoubleEq(0.0)));
}

TEST(ReadImageFolder, EurocImageFolderMatchesEurocReader) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  ImageFolderOptions options;
  options.camera_yaml = root / "mav0/cam0/sensor.yaml";
  const Sequence folder = ReadImageFolder(root / "mav0/cam0/data", options);
  const Sequence euroc = ReadEurocDataset(root);
  ASSERT_EQ(folder.images.size(), 95u);
  ASSERT_EQ(euroc.images.size(), 95u);
  for (size_t i = 0; i < folder.images.size(); ++i) {
    EXPECT_EQ(folder.images[i].timestamp_ns, euroc.images[i].timestamp_ns);
    EXPECT_EQ(folder.images[i].path, euroc.images[i].path);
  }
  EXPECT_EQ(folder.rig.camera.params, euroc.rig.camera.params);
}

TEST(ReadImageFolder, Errors) {
  const fs::path folder = testing::MakeScratchFolder("images_errors");
  const ImageFolderOptions options = PinholeOptions();

  // Missing and empty folders.
  EXPECT_THAT(ExpectInputError([&] { ReadImageFolder(folder / "absent", options); }).what(),
              HasSubstr("image folder does not exist"));
  WriteTextFile(folder / "readme.txt", "x");
  InputError error = ExpectInputError([&] { ReadImageFolder(folder, options); });
  EXPECT_EQ(error.path(), folder.string());
  EXPECT_THAT(error.what(), HasSubstr("found none"));

  // Duplicate stamps: 01000000100 and 1000000100.
  WriteTextFile(folder / "1000000100.png", "x");
  WriteTextFile(folder / "01000000100.jpg", "x");
  error = ExpectInputError([&] { ReadImageFolder(folder, options); });
  EXPECT_EQ(error.path(), (folder / "1000000100.png").string());
  EXPECT_THAT(error.what(), HasSubstr("duplicate timestamp 1000000100 ns, also given by " +
                                      (folder / "01000000100.jpg").string()));

  // Timestamps file problems, each on line 3.
  ImageFolderOptions with_file = options;
  with_file.timestamps_file = folder / "times.txt";
  struct Case {
    std::string line3;
    std::string expected;
  };
  const Case cases[] = {
      {"missing.png 200", "listed image 'missing.png' does not exist"},
      {"01000000100.jpg 100",
       "duplicate timestamp 100 ns, also given by " + (folder / "times.txt").string() + ":2"},
      {"01000000100.jpg 1e5", "got '1e5'"},
      {"01000000100.jpg 12abc", "got '12abc'"},
      {"01000000100.jpg", "expected 'filename timestamp'"},
      {"01000000100.jpg 5 6", "got 3 fields"},
      {"1000000100.png 300", "already listed on line 2"},
  };
  for (const Case& c : cases) {
    WriteTextFile(folder / "times.txt", "# header\n1000000100.png 100\n" + c.line3 + "\n");
    error = ExpectInputError([&] { ReadImageFolder(folder, with_file); });
    EXPECT_EQ(error.path(), (folder / "times.txt").string()) << c.line3;
    EXPECT_EQ(error.line(), 3) << c.line3;
    EXPECT_THAT(error.what(), HasSubstr(c.expected)) << c.line3;
  }
  WriteTextFile(folder / "times.txt", "# nothing\n");
  EXPECT_THAT(ExpectInputError([&] { ReadImageFolder(folder, with_file); }).what(),
              HasSubstr("found none"));

  // Options.
  ImageFolderOptions two_cameras = options;
  two_cameras.camera_yaml = folder / "sensor.yaml";
  EXPECT_THAT(ExpectInputError([&] { ReadImageFolder(folder, two_cameras); }).what(),
              HasSubstr("at most one of camera and camera_yaml"));
  ImageFolderOptions bad_camera = options;
  bad_camera.camera->params.pop_back();
  EXPECT_FALSE(bad_camera.Check());
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

TEST(ImageFolder, EstimatesTheFrameRateFromStamps) {
  const std::filesystem::path folder = testing::MakeScratchFolder("image_folder_rate");
  for (int i = 0; i < 6; ++i) {
    std::ofstream(folder / (std::to_string(1000000000 + i * 100000000 + (i == 3 ? 7 : 0)) + ".png"))
        << "x";
  }
  ImageFolderOptions options;
  options.camera = MakeCamera(CameraModelId::kPinhole, 64, 48, {50, 50, 32, 24});
  const Sequence sequence = ReadImageFolder(folder, options);
  ASSERT_EQ(sequence.images.size(), 6u);
  EXPECT_DOUBLE_EQ(sequence.rig.camera_rate_hz, 10.0);  // median interval 100 ms
  EXPECT_DOUBLE_EQ(EstimateFrameRateHz({}), 0.0);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/io/dataset_checks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "viosfm/io/image_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Writes `text` to `path`, creating its folders.
void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  testing::WriteTextFile(path, text);
}

using ::testing::HasSubstr;
using testing::InputErrorMessage;

ImuSample Sample(double accel_z, double gyro_x) {
  ImuSample sample;
  sample.accel = Eigen::Vector3d(0.0, 0.0, accel_z);
  sample.gyro = Eigen::Vector3d(gyro_x, 0.0, 0.0);
  return sample;
}

TEST(CheckImuSample, AcceptsWhatAnImuMeasuresAndNamesFileAndLineBeyond) {
  const DatasetChecks checks;
  EXPECT_NEAR(checks.imu_max_accel_m_s2, 490.3325, 1e-9);  // 50 g
  // A 16 g shock and a 2000 deg/s spin are measurements.
  CheckImuSample(Sample(16 * kOneG, 2000.0 * M_PI / 180.0), checks, "imu.csv", 7);
  CheckImuSample(Sample(-checks.imu_max_accel_m_s2, -checks.imu_max_gyro_rad_s), checks, "imu.csv",
                 7);
  const std::string accel =
      InputErrorMessage([&] { CheckImuSample(Sample(1e6, 0.0), checks, "imu.csv", 7); });
  EXPECT_THAT(accel, HasSubstr("imu.csv:7: acceleration a_z = 1e+06 m/s^2 is beyond"));
  EXPECT_THAT(accel, HasSubstr("dataset_checks.imu_max_accel_m_s2"));
  const std::string gyro =
      InputErrorMessage([&] { CheckImuSample(Sample(9.81, -36.0), checks, "imu.csv", 9); });
  EXPECT_THAT(gyro, HasSubstr("imu.csv:9: angular rate w_x = -36 rad/s is beyond"));
  for (const double hostile : {1e308, 1e30, 1e12, std::numeric_limits<double>::infinity(),
                               std::numeric_limits<double>::quiet_NaN()}) {
    InputErrorMessage([&] { CheckImuSample(Sample(hostile, 0.0), checks, "imu.csv", 3); });
    InputErrorMessage([&] { CheckImuSample(Sample(9.81, hostile), checks, "imu.csv", 3); });
  }
  // Raised bounds (an impact IMU) accept it.
  DatasetChecks wide;
  wide.imu_max_accel_m_s2 = 2e6;
  CheckImuSample(Sample(1e6, 0.0), wide, "imu.csv", 7);
  wide.imu_max_gyro_rad_s = 0.0;
  EXPECT_THAT(wide.Validate(), HasSubstr("imu_max_gyro_rad_s"));
}

TEST(FindImuGaps, ReportsEveryGapLongerThanTheStepAndNothingElse) {
  std::vector<ImuSample> samples;
  for (timestamp_ns_t t = 0; t <= 2'000'000'000; t += 5'000'000) {
    // A dropped sample at 0.5 s (10 ms), a 1 s gap from 1.0 s, 0.15 s from 1.8 s.
    if (t == 500'000'000) continue;
    if (t > 1'000'000'000 && t < 2'000'000'000 - 200'000'000) continue;
    if (t > 1'800'000'000 && t < 1'950'000'000) continue;
    ImuSample sample;
    sample.timestamp_ns = t;
    samples.push_back(sample);
  }
  const std::vector<ImuGap> gaps = FindImuGaps(samples, kImuGapReportNs);
  ASSERT_EQ(gaps.size(), 2u);
  EXPECT_EQ(gaps[0].from_ns, 1'000'000'000);
  EXPECT_EQ(gaps[0].to_ns, 1'800'000'000);
  EXPECT_EQ(samples[gaps[0].index].timestamp_ns, 1'800'000'000);
  EXPECT_EQ(gaps[1].length_ns(), 150'000'000);
  EXPECT_EQ(DescribeImuGaps(gaps, samples, kImuGapReportNs),
            "2 gap(s) longer than 0.100 s without samples (0.950 s in all; the longest 0.800 s, "
            "from 1.000 s after the first sample)");
  EXPECT_EQ(FindImuGaps(samples, 5'000'000).size(), 3u);  // the dropped sample too
  EXPECT_TRUE(FindImuGaps({}, kImuGapReportNs).empty());
  EXPECT_EQ(DescribeImuGaps({}, samples, kImuGapReportNs), "");
}

Camera EurocCamera() {
  return MakeCamera(
      CameraModelId::kOpenCV, 752, 480,
      {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}

TEST(CheckCameraCalibration, AcceptsRealCalibrations) {
  EXPECT_EQ(CheckCameraCalibration(EurocCamera()), "");
  EXPECT_EQ(
      CheckCameraCalibration(MakeCamera(CameraModelId::kPinhole, 640, 480, {500, 500, 320, 240})),
      "");
  // TUM-VI's fisheye: its corners lie beyond 90 degrees from the axis.
  EXPECT_EQ(CheckCameraCalibration(MakeCamera(CameraModelId::kOpenCVFisheye, 512, 512,
                                              {190.978, 190.973, 254.932, 256.897, 0.0034823894,
                                               0.000715034, -0.0020532361, 0.000202936})),
            "");
}

TEST(CheckCameraCalibration, RefusesWhatNoCameraIs) {
  Camera camera = EurocCamera();
  camera.params[2] = -5000.0;
  EXPECT_THAT(CheckCameraCalibration(camera),
              HasSubstr("principal point (-5000, 248.375) px is outside the 752x480 image"));
  camera = EurocCamera();
  camera.params[3] = 1e9;
  EXPECT_THAT(CheckCameraCalibration(camera), HasSubstr("is outside the 752x480 image"));
  // A k1 of 1e200 squeezes the whole image into a pinpoint of view (or
  // overflows): no lens.
  camera = EurocCamera();
  camera.params[4] = 1e200;
  EXPECT_NE(CheckCameraCalibration(camera), "");
  // k1 = -0.5 alone: the distorted radius peaks at 0.54 and comes back, so
  // the image's outer part is folded (no ray reaches it).
  camera = EurocCamera();
  camera.params[4] = -0.5;
  camera.params[5] = 0.0;
  EXPECT_THAT(CheckCameraCalibration(camera), HasSubstr("folds the image"));
  camera = EurocCamera();
  camera.params[0] = -458.0;
  EXPECT_THAT(CheckCameraCalibration(camera), HasSubstr("must be positive"));
}

TEST(CheckRigTranslation, TenMetres) {
  Rigid3d body_from_cam;
  body_from_cam.translation = Eigen::Vector3d(0.1, 0.02, -9.9);
  EXPECT_EQ(CheckRigTranslation(body_from_cam), "");
  body_from_cam.translation.z() = 1e300;
  EXPECT_THAT(CheckRigTranslation(body_from_cam), HasSubstr("translation is 1e+300 m"));
}

TEST(CheckInsideDataset, LinksLeavingTheDatasetAreRefusedUnlessAllowed) {
  const fs::path scratch = testing::MakeScratchFolder("inside_dataset");
  const fs::path dataset = scratch / "dataset";
  Write(dataset / "data" / "a.png", "a");
  Write(scratch / "secret.png", "s");
  fs::create_symlink("a.png", dataset / "data" / "inside.png");
  fs::create_symlink(scratch / "secret.png", dataset / "data" / "outside.png");
  const DatasetChecks checks;
  EXPECT_EQ(CheckInsideDataset(dataset, dataset / "data" / "inside.png", checks, ""),
            fs::canonical(dataset / "data" / "a.png"));
  const std::string message = InputErrorMessage(
      [&] { CheckInsideDataset(dataset, dataset / "data" / "outside.png", checks, "data.csv:3"); });
  EXPECT_THAT(message, HasSubstr((dataset / "data" / "outside.png").string() +
                                 ": named by data.csv:3: leads outside the dataset"));
  EXPECT_THAT(message, HasSubstr("--allow-external-links"));
  DatasetChecks allowed;
  allowed.allow_links_outside = true;
  EXPECT_EQ(CheckInsideDataset(dataset, dataset / "data" / "outside.png", allowed, ""),
            fs::canonical(scratch / "secret.png"));
  // A prefix of the folder's name is not the folder.
  Write(scratch / "dataset2" / "x.png", "x");
  fs::create_symlink(scratch / "dataset2" / "x.png", dataset / "data" / "sibling.png");
  InputErrorMessage(
      [&] { CheckInsideDataset(dataset, dataset / "data" / "sibling.png", checks, ""); });
}

TEST(CheckSequenceImages, OneFileUnderTwoStampsAndAWrongHeaderSizeAreRefused) {
  const fs::path dataset = testing::MakeScratchFolder("sequence_images");
  GreyImage image(64, 48);
  WriteGreyPng(dataset / "a.png", image);
  WriteGreyPng(dataset / "b.png", image);
  fs::create_symlink("a.png", dataset / "c.png");
  Sequence sequence;
  sequence.rig.camera = MakeCamera(CameraModelId::kPinhole, 64, 48, {50, 50, 32, 24});
  sequence.images = {{1, dataset / "a.png"}, {2, dataset / "b.png"}};
  CheckSequenceImages(sequence, dataset, DatasetChecks());
  sequence.images.push_back({3, dataset / "c.png"});
  EXPECT_THAT(InputErrorMessage([&] { CheckSequenceImages(sequence, dataset, DatasetChecks()); }),
              HasSubstr("is the same file as " + (dataset / "a.png").string()));
  sequence.images.pop_back();
  sequence.rig.camera.width = 640;
  EXPECT_THAT(InputErrorMessage([&] { CheckSequenceImages(sequence, dataset, DatasetChecks()); }),
              HasSubstr("a.png: the image is 64x48 pixels (its header says), the camera's "
                        "calibration 640x48"));
}

}  // namespace
}  // namespace viosfm

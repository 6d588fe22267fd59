#include "viosfm/io/kalibr.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "viosfm/io/euroc.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using testing::ExpectInputError;
using ::testing::HasSubstr;
using testing::WriteTextFile;

// cam_from_imu of the synthetic camchain: a rotation of 90 degrees about z
// and a translation, written out in the rows of T_cam_imu.
Rigid3d SyntheticCamFromImu() {
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
                 Eigen::Vector3d(0.1, -0.2, 0.05));
}

// A camchain as Kalibr writes it (camchain-imucam.yaml), with `tail`
// appended to cam0.
std::string SyntheticCamchain(const std::string& tail = "") {
  return "cam0:\n"
         "  T_cam_imu:\n"
         "  - [0.0, -1.0, 0.0, 0.1]\n"
         "  - [1.0, 0.0, 0.0, -0.2]\n"
         "  - [0.0, 0.0, 1.0, 0.05]\n"
         "  - [0.0, 0.0, 0.0, 1.0]\n"
         "  cam_overlaps: []\n"
         "  camera_model: pinhole\n"
         "  distortion_coeffs: [-0.28, 0.07, 0.0002, 1.8e-05]\n"
         "  distortion_model: radtan\n"
         "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
         "  resolution: [752, 480]\n"
         "  rostopic: /cam0/image_raw\n" +
         tail;
}

constexpr char kImuYaml[] =
    "#Accelerometers\n"
    "accelerometer_noise_density: 1.86e-03   #Noise density (continuous-time)\n"
    "accelerometer_random_walk:   4.33e-04   #Bias random walk\n"
    "#Gyroscopes\n"
    "gyroscope_noise_density:     1.87e-04   #Noise density (continuous-time)\n"
    "gyroscope_random_walk:       2.66e-05   #Bias random walk\n"
    "rostopic:                    /imu0      #the IMU ROS topic\n"
    "update_rate:                 200.0      #Hz (for discretization of the values above)\n";

TEST(ReadKalibrCalibration, ReadsCam0AndInvertsTCamImu) {
  const fs::path folder = testing::MakeScratchFolder("kalibr_synthetic");
  WriteTextFile(folder / "camchain.yaml", SyntheticCamchain("  timeshift_cam_imu: 0.0021\n"));
  const KalibrCalibration calibration = ReadKalibrCalibration(folder / "camchain.yaml");
  ASSERT_TRUE(calibration.camera.has_value());
  EXPECT_EQ(calibration.camera->model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(calibration.camera->width, 752u);
  EXPECT_EQ(calibration.camera->height, 480u);
  EXPECT_THAT(calibration.camera->params,
              ElementsAre(458.654, 457.296, 367.215, 248.375, -0.28, 0.07, 0.0002, 1.8e-05));
  // body = IMU: body_from_cam = T_cam_imu^-1. A point 1 m along the camera's
  // x axis: in the IMU frame, x_imu = R^T (x_cam - t).
  const Rigid3d cam_from_imu = SyntheticCamFromImu();
  const Eigen::Vector3d point_in_cam(1.0, 0.0, 0.0);
  const Eigen::Vector3d expected =
      cam_from_imu.rotation.inverse() * (point_in_cam - cam_from_imu.translation);
  EXPECT_LT((calibration.body_from_cam * point_in_cam - expected).norm(), 1e-15);
  EXPECT_LT((calibration.body_from_cam * point_in_cam - Eigen::Vector3d(0.2, -0.9, -0.05)).norm(),
            1e-15);
  // t_imu = t_cam + 2.1 ms.
  EXPECT_EQ(calibration.cam_time_offset_ns, 2'100'000);
  EXPECT_FALSE(calibration.imu_noise.has_value());
}

TEST(ReadKalibrCalibration, ImuFileAndNoiseInsideCam0) {
  const fs::path folder = testing::MakeScratchFolder("kalibr_imu");
  WriteTextFile(folder / "imu.yaml", kImuYaml);
  WriteTextFile(folder / "camchain.yaml", SyntheticCamchain());
  KalibrCalibration calibration =
      ReadKalibrCalibration(folder / "camchain.yaml", folder / "imu.yaml");
  ASSERT_TRUE(calibration.imu_noise.has_value());
  EXPECT_EQ(calibration.imu_noise->accel_noise_density, 1.86e-03);
  EXPECT_EQ(calibration.imu_noise->accel_random_walk, 4.33e-04);
  EXPECT_EQ(calibration.imu_noise->gyro_noise_density, 1.87e-04);
  EXPECT_EQ(calibration.imu_noise->gyro_random_walk, 2.66e-05);
  EXPECT_EQ(calibration.imu_noise->update_rate_hz, 200.0);
  EXPECT_EQ(calibration.cam_time_offset_ns, 0);  // no timeshift_cam_imu

  // Kalibr's imu0: form.
  WriteTextFile(folder / "imu0.yaml",
                "imu0:\n  accelerometer_noise_density: 0.01\n  accelerometer_random_walk: 0.002\n"
                "  gyroscope_noise_density: 0.0003\n  gyroscope_random_walk: 4.0e-06\n"
                "  model: calibrated\n  time_offset: 0.0\n");
  const KalibrImuNoise imu0 = ReadKalibrImuYaml(folder / "imu0.yaml");
  EXPECT_EQ(imu0.accel_noise_density, 0.01);
  EXPECT_EQ(imu0.gyro_random_walk, 4.0e-06);
  EXPECT_FALSE(imu0.update_rate_hz.has_value());

  // Noise inside cam0 (as the DM-VIO camchain has it), no IMU file.
  WriteTextFile(folder / "camchain_noise.yaml",
                SyntheticCamchain("  accelerometer_noise_density: 0.18\n"
                                  "  accelerometer_random_walk: 0.024\n"
                                  "  gyroscope_noise_density: 3.7e-05\n"
                                  "  gyroscope_random_walk: 2.6e-06\n"));
  calibration = ReadKalibrCalibration(folder / "camchain_noise.yaml");
  ASSERT_TRUE(calibration.imu_noise.has_value());
  EXPECT_EQ(calibration.imu_noise->accel_noise_density, 0.18);
  EXPECT_EQ(calibration.imu_noise_path, folder / "camchain_noise.yaml");
  // With an IMU file too, the IMU file wins.
  calibration = ReadKalibrCalibration(folder / "camchain_noise.yaml", folder / "imu.yaml");
  EXPECT_EQ(calibration.imu_noise->accel_noise_density, 1.86e-03);
  EXPECT_EQ(calibration.imu_noise_path, folder / "imu.yaml");
}

TEST(ReadKalibrCalibration, ErrorsNameFileLineAndExpectation) {
  const fs::path folder = testing::MakeScratchFolder("kalibr_errors");
  const fs::path path = folder / "camchain.yaml";
  struct Case {
    std::string text;
    int64_t line;
    std::string expected;
  };
  const std::string mirrored =
      "cam0:\n  T_cam_imu:\n  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, -1, 0]\n"
      "  - [0, 0, 0, 1]\n";
  const Case cases[] = {
      {"cam1:\n  resolution: [1, 1]\n", 1, "expected a Kalibr camchain with a 'cam0:' map"},
      {"cam0: 3\n", 1, "'cam0': expected a map"},
      {"cam0:\n  intrinsics: [1, 1, 0, 0]\n", 2, "'T_cam_imu': required key is missing"},
      {mirrored, 3, "determinant is -1 (a reflection"},
      {SyntheticCamchain("  timeshift_cam_imu: 2.5\n"), 14,
       "'timeshift_cam_imu': expected a camera-IMU time offset of at most 1 s"},
      {SyntheticCamchain("  timeshift_cam_imu: .nan\n"), 14, "expected a finite number"},
      // A missing key is reported at the line of the map that lacks it.
      {SyntheticCamchain("  accelerometer_noise_density: 0.1\n"), 2,
       "'accelerometer_random_walk': required key is missing"},
      {SyntheticCamchain("  accelerometer_noise_density: -0.1\n  accelerometer_random_walk: 1\n"
                         "  gyroscope_noise_density: 1\n  gyroscope_random_walk: 1\n"),
       14, "'accelerometer_noise_density': expected a positive number"},
      {"cam0:\n  T_cam_imu: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
       "  camera_model: omni\n  intrinsics: [1, 1, 1, 0, 0]\n  resolution: [10, 10]\n",
       3, "unknown camera model 'omni'"},
      {"cam0:\n  T_cam_imu: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
       "  distortion_model: radtan\n  distortion_coeffs: [0.1]\n"
       "  intrinsics: [1, 1, 0, 0]\n  resolution: [10, 10]\n",
       4, "'distortion_coeffs': distortion_model 'radtan' expects 4 coefficients"},
      {"cam0:\n  T_cam_imu: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
       "  intrinsics: [1, 1, 0, 0]\n",
       2, "'resolution': required key is missing"},
      {"cam0: [unclosed\n", 2, "invalid YAML"},
  };
  for (const Case& c : cases) {
    WriteTextFile(path, c.text);
    const InputError error = ExpectInputError([&] { ReadKalibrCalibration(path); });
    EXPECT_EQ(error.path(), path.string()) << c.text;
    EXPECT_EQ(error.line(), c.line) << c.text << "\n" << error.what();
    EXPECT_THAT(error.what(), HasSubstr(c.expected)) << c.text;
  }
  WriteTextFile(folder / "imu.yaml", "rostopic: /imu0\n");
  EXPECT_THAT(ExpectInputError([&] { ReadKalibrImuYaml(folder / "imu.yaml"); }).what(),
              HasSubstr("expected a Kalibr IMU file"));
  EXPECT_THAT(ExpectInputError([&] { ReadKalibrCalibration(folder / "absent.yaml"); }).what(),
              HasSubstr("does not exist"));
}

// A sequence with EuRoC-like calibration, to be replaced.
Sequence MakeSequence() {
  Sequence sequence;
  sequence.rig.camera.camera_id = 1;
  sequence.rig.camera.model_id = CameraModelId::kPinhole;
  sequence.rig.camera.width = 640;
  sequence.rig.camera.height = 480;
  sequence.rig.camera.params = {500, 500, 320, 240};
  sequence.rig.body_from_cam = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 3));
  sequence.rig.imu_noise.rate_hz = 400.0;
  return sequence;
}

TEST(ApplyCalibration, ReplacesExtrinsicsCameraNoiseAndTimeOffset) {
  const fs::path folder = testing::MakeScratchFolder("kalibr_apply");
  WriteTextFile(folder / "camchain.yaml", SyntheticCamchain("  timeshift_cam_imu: -0.0035\n"));
  WriteTextFile(folder / "imu.yaml", kImuYaml);
  Sequence sequence = MakeSequence();
  EXPECT_EQ(sequence.rig.CamToImuTime(1'000'000'000), 1'000'000'000);
  ApplyCalibrationFiles({folder / "camchain.yaml", folder / "imu.yaml"}, &sequence);
  const SensorRig& rig = sequence.rig;
  EXPECT_EQ(rig.camera.camera_id, 1u);
  EXPECT_EQ(rig.camera.model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(rig.camera.width, 752u);
  EXPECT_LT((rig.body_from_cam.ToMatrix() - SyntheticCamFromImu().Inverse().ToMatrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-15);
  // The shift moves a camera stamp on the IMU clock: t_imu = t_cam - 3.5 ms.
  EXPECT_EQ(rig.cam_time_offset_ns, -3'500'000);
  EXPECT_EQ(rig.CamToImuTime(1'000'000'000), 996'500'000);
  EXPECT_EQ(rig.imu_noise.gyro_noise_density, 1.87e-04);
  EXPECT_EQ(rig.imu_noise.rate_hz, 200.0);

  // Extrinsics only: the camera and the IMU noise stay the dataset's.
  WriteTextFile(folder / "extrinsics.yaml",
                "cam0:\n  T_cam_imu: [[1, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n");
  sequence = MakeSequence();
  const Sequence before = sequence;
  ApplyCalibrationFiles({folder / "extrinsics.yaml", {}}, &sequence);
  EXPECT_EQ(sequence.rig.camera.params, before.rig.camera.params);
  EXPECT_EQ(sequence.rig.imu_noise.gyro_noise_density, before.rig.imu_noise.gyro_noise_density);
  EXPECT_EQ(sequence.rig.imu_noise.rate_hz, 400.0);
  EXPECT_EQ(sequence.rig.body_from_cam.translation, Eigen::Vector3d(-0.5, 0, 0));

  // Nothing given: nothing changes; an IMU file alone is refused.
  sequence = MakeSequence();
  ApplyCalibrationFiles({}, &sequence);
  EXPECT_EQ(sequence.rig.body_from_cam.translation, Eigen::Vector3d(1, 2, 3));
  EXPECT_THAT(ExpectInputError([&] {
                ApplyCalibrationFiles({{}, folder / "imu.yaml"}, &sequence);
              }).what(),
              HasSubstr("needs the camchain"));
}

// The recording's own Kalibr files: the numbers are the files' and T_BS of
// its EuRoC sensor.yaml (written from the same calibration) is T_cam_imu^-1.
TEST(ReadKalibrCalibration, RealsenseRoomCalibration) {
  VIOSFM_REQUIRE_DATASET(root, "realsense_room_30s");
  const fs::path camchain = root / "calibration/camchain.yaml";
  const fs::path imu = root / "calibration/d515.yaml";
  const KalibrCalibration calibration = ReadKalibrCalibration(camchain, imu);
  EXPECT_FALSE(calibration.camera.has_value());  // this camchain holds no intrinsics
  EXPECT_EQ(calibration.cam_time_offset_ns, 0);  // nor a timeshift_cam_imu
  ASSERT_TRUE(calibration.imu_noise.has_value());
  EXPECT_EQ(calibration.imu_noise->accel_noise_density, 0.1829589017330412);
  EXPECT_EQ(calibration.imu_noise->accel_random_walk, 0.024480362284765463);
  EXPECT_EQ(calibration.imu_noise->gyro_noise_density, 3.7425273003024506e-05);
  EXPECT_EQ(calibration.imu_noise->gyro_random_walk, 2.5996760318842082e-06);
  EXPECT_FALSE(calibration.imu_noise->update_rate_hz.has_value());

  Eigen::Matrix4d cam_from_imu;
  cam_from_imu << 0.99994214, 0.00945273, -0.0050503, 0.01205559,  //
      -0.00932683, 0.99965867, 0.02439719, -0.00234671,            //
      0.00527919, -0.02434868, 0.99968917, -0.00226012,            //
      0, 0, 0, 1;
  // The file's rotation has 8 decimals and is orthonormal to about 1e-7;
  // inverting the matrix itself agrees with the inverted rigid transform
  // (projected onto the nearest rotation) to that.
  const Eigen::Matrix4d expected = cam_from_imu.inverse();
  EXPECT_LT((calibration.body_from_cam.ToMatrix() - expected.topRows<3>()).cwiseAbs().maxCoeff(),
            1e-6);
  const Rigid3d sensor_yaml_body_from_cam =
      ReadEurocSensorTransform(root / "mav0/cam0/sensor.yaml");
  EXPECT_LT((calibration.body_from_cam.ToMatrix() - sensor_yaml_body_from_cam.ToMatrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-6);

  // Applied to the dataset: the same rig as its own sensor.yaml files give.
  EurocReadOptions options;
  options.check_images_exist = false;
  Sequence sequence = ReadEurocDataset(root, options);
  const SensorRig own = sequence.rig;
  ApplyCalibrationFiles({camchain, imu}, &sequence);
  EXPECT_EQ(sequence.rig.camera.params, own.camera.params);
  EXPECT_EQ(sequence.rig.imu_noise.accel_noise_density, own.imu_noise.accel_noise_density);
  EXPECT_EQ(sequence.rig.imu_noise.rate_hz, own.imu_noise.rate_hz);
  EXPECT_LT(sequence.rig.body_from_cam.rotation.angularDistance(own.body_from_cam.rotation), 1e-6);
  EXPECT_LT((sequence.rig.body_from_cam.translation - own.body_from_cam.translation).norm(), 1e-6);
}

}  // namespace
}  // namespace viosfm

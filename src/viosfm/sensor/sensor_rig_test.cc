#include "viosfm/sensor/sensor_rig.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "viosfm/sensor/camera_models.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// EuRoC MAV: cam0 intrinsics and T_BS (body = IMU).
SensorRig EurocRig() {
  SensorRig rig;
  rig.camera = MakeCamera(
      CameraModelId::kOpenCV, 752, 480,
      {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
  Eigen::Matrix<double, 3, 4> body_from_cam;
  body_from_cam << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
      0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,  //
      -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949;
  rig.body_from_cam = Rigid3d::FromMatrix(body_from_cam);
  return rig;
}

TEST(SensorRig, EurocRigIsValid) {
  const SensorRig rig = EurocRig();
  EXPECT_EQ(rig.Validate(), "");
  EXPECT_TRUE(rig.Check());
  // The camera centre in the body frame is T_BS's translation.
  EXPECT_LT((rig.body_from_cam * Eigen::Vector3d::Zero() -
             Eigen::Vector3d(-0.0216401454975, -0.064676986768, 0.00981073058949))
                .norm(),
            1e-15);
  EXPECT_LT((rig.cam_from_body() * (rig.body_from_cam * Eigen::Vector3d(1, 2, 3)) -
             Eigen::Vector3d(1, 2, 3))
                .norm(),
            1e-14);
}

TEST(SensorRig, TimeOffset) {
  SensorRig rig = EurocRig();
  rig.cam_time_offset_ns = -1500;
  EXPECT_EQ(rig.CamToImuTime(1403715273262142976), 1403715273262141476);
}

TEST(SensorRig, ValidateCatchesNonUnitQuaternion) {
  SensorRig rig = EurocRig();
  rig.body_from_cam.rotation.coeffs() *= 1.01;
  EXPECT_THAT(rig.Validate(), StartsWith("body_from_cam.rotation: quaternion norm 1.01"));
  rig.body_from_cam.rotation.coeffs() /= 1.01;
  EXPECT_EQ(rig.Validate(), "");
  rig.body_from_cam.rotation.coeffs().setZero();
  EXPECT_THAT(rig.Validate(), StartsWith("body_from_cam.rotation"));
  rig = EurocRig();
  rig.body_from_cam.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(rig.Validate(), StartsWith("body_from_cam.translation"));
}

TEST(SensorRig, ValidateCatchesBadCamera) {
  SensorRig rig = EurocRig();
  rig.camera.params.pop_back();
  EXPECT_THAT(rig.Validate(), HasSubstr("camera: model OPENCV expects 8 parameters, got 7"));

  rig = EurocRig();
  rig.camera.model_id = CameraModelId::kThinPrismFisheye;
  rig.camera.params.resize(12, 0.0);
  EXPECT_THAT(rig.Validate(), HasSubstr("THIN_PRISM_FISHEYE"));

  rig = EurocRig();
  rig.camera.width = 0;
  EXPECT_THAT(rig.Validate(), HasSubstr("image size 0x480"));

  rig = EurocRig();
  rig.camera.params[1] = -457.296;
  EXPECT_THAT(rig.Validate(), HasSubstr("focal length (parameter 1)"));

  rig = EurocRig();
  rig.camera.params[5] = std::numeric_limits<double>::infinity();
  EXPECT_THAT(rig.Validate(), HasSubstr("parameter 5 is not finite"));

  rig = EurocRig();
  rig.camera = Camera();  // default: invalid model
  EXPECT_THAT(rig.Validate(), StartsWith("camera:"));
}

TEST(SensorRig, ValidateCatchesBadImuNoiseAndRate) {
  SensorRig rig = EurocRig();
  rig.imu_noise.accel_noise_density = -1.0;
  EXPECT_THAT(rig.Validate(), StartsWith("imu_noise: accel_noise_density"));
  rig = EurocRig();
  rig.camera_rate_hz = 0.0;
  EXPECT_THAT(rig.Validate(), StartsWith("camera_rate_hz"));
}

}  // namespace
}  // namespace viosfm

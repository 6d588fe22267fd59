#include "viosfm/scene/rolling_shutter.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// Where a rolling-shutter camera turning at `rate` (its own frame) sees the
// point whose bearing at the stamp is `bearing`: its row is exposed
// RowTimeOffset(row) after the stamp, when the camera has turned by
// Exp(rate * dt), so the bearing is Exp(-rate * dt) * bearing; the row and
// the projection are solved together (a fixed point).
Eigen::Vector2d RollingShutterPixel(const Camera& camera, const Eigen::Vector3d& bearing,
                                    const Eigen::Vector3d& rate, double readout_s) {
  Eigen::Vector2d pixel = CamToImage(camera, bearing.hnormalized());
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double dt = RowTimeOffset(pixel.y(), static_cast<int>(camera.height), readout_s);
    const Eigen::Vector3d turned =
        Eigen::AngleAxisd(rate.norm() * dt, rate.normalized()).inverse() * bearing;
    pixel = CamToImage(camera, turned.hnormalized());
  }
  return pixel;
}

TEST(RollingShutter, RowTimeOffsetIsZeroAtTheMiddleRow) {
  EXPECT_NEAR(RowTimeOffset(239.5, 480, 0.02), 0.0, 1e-15);
  EXPECT_NEAR(RowTimeOffset(-0.5, 480, 0.02), -0.01, 1e-15);
  EXPECT_NEAR(RowTimeOffset(479.5, 480, 0.02), 0.01, 1e-15);
}

// A camera with radial-tangential distortion turning at 2 rad/s, read out
// in 20 ms: keypoints are up to ~9 px from where a global shutter at the
// stamp would see them; compensated, within 0.002 px.
TEST(RollingShutter, CompensationPutsKeypointsWhereTheStampSeesThem) {
  const Camera camera = MakeCamera(CameraModelId::kOpenCV, 752, 480,
                                   {458.0, 457.0, 367.0, 248.0, -0.28, 0.07, 2e-4, 2e-5});
  const Eigen::Vector3d rate = Eigen::Vector3d(0.4, -1.9, 0.5);
  const double readout_s = 0.02;
  Random random(3);
  FeatureKeypoints keypoints;
  std::vector<Eigen::Vector2d> at_stamp;
  double max_shift_px = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d target(random.Uniform(40.0, 712.0), random.Uniform(30.0, 450.0));
    const Eigen::Vector3d bearing = ImageToCam(camera, target).homogeneous();
    const Eigen::Vector2d seen = RollingShutterPixel(camera, bearing, rate, readout_s);
    FeatureKeypoint keypoint;
    keypoint.x = static_cast<float>(seen.x());
    keypoint.y = static_cast<float>(seen.y());
    keypoint.a11 = 2.0f;
    keypoints.push_back(keypoint);
    at_stamp.push_back(target);
    max_shift_px = std::max(max_shift_px, (seen - target).norm());
  }
  EXPECT_GT(max_shift_px, 5.0);
  CompensateRollingShutterRotation(camera, readout_s, rate, &keypoints);
  for (size_t k = 0; k < keypoints.size(); ++k) {
    EXPECT_LT((Eigen::Vector2d(keypoints[k].x, keypoints[k].y) - at_stamp[k]).norm(), 2e-3) << k;
    EXPECT_EQ(keypoints[k].a11, 2.0f);
  }
}

TEST(RollingShutter, GlobalShutterOrNoTurnChangesNothing) {
  const Camera camera = MakeCamera(CameraModelId::kPinhole, 640, 480, {500.0, 500.0, 320.0, 240.0});
  FeatureKeypoints keypoints(1);
  keypoints[0].x = 10.0f;
  keypoints[0].y = 20.0f;
  CompensateRollingShutterRotation(camera, 0.0, Eigen::Vector3d(1.0, 2.0, 3.0), &keypoints);
  CompensateRollingShutterRotation(camera, 0.03, Eigen::Vector3d::Zero(), &keypoints);
  EXPECT_NEAR(keypoints[0].x, 10.0f, 1e-4);
  EXPECT_NEAR(keypoints[0].y, 20.0f, 1e-4);
}

// The gyro's rate, on the IMU's clock and turned into the camera frame.
TEST(RollingShutter, CamAngularRateIsTheGyroInTheCameraFrame) {
  SensorRig rig;
  rig.body_from_cam.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  rig.cam_time_offset_ns = 50'000'000;  // t_imu = t_cam + 50 ms
  std::vector<ImuSample> imu;
  for (int k = 0; k < 100; ++k) {
    ImuSample sample;
    sample.timestamp_ns = k * 5'000'000;
    // 1 rad/s about the body's x until 0.2 s (IMU clock), then about z.
    sample.gyro =
        sample.timestamp_ns < 200'000'000 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    imu.push_back(sample);
  }
  // Camera time 0.1 s is IMU time 0.15 s: about the body's x, which is the
  // camera's -y.
  EXPECT_LT((CamAngularRate(rig, imu, 100'000'000) - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  // Camera time 0.3 s is IMU time 0.35 s: about z.
  EXPECT_LT((CamAngularRate(rig, imu, 300'000'000) - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12);
  EXPECT_EQ(CamAngularRate(rig, {}, 0), Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace viosfm

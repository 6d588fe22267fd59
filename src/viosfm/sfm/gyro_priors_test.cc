#include "viosfm/sfm/gyro_priors.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <vector>

#include "viosfm/geometry/lie.h"
#include "viosfm/sfm/synthetic_imu_walk.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// The walk's rotation: WalkWorldFromBody (synthetic_imu_walk.h).
const Eigen::Vector3d kGyroBias(0.002, -0.001, 0.003);

// 200 Hz gyro over [0, duration] with EuRoC-like noise and a constant bias
// (the accelerometer is not used).
std::vector<ImuSample> MakeGyro(double duration_s, const ImuNoise& noise, uint64_t seed) {
  Random random(seed);
  std::vector<ImuSample> imu;
  const double dt = 1.0 / noise.rate_hz;
  const double h = 1e-5;
  for (int k = 0; k * dt <= duration_s; ++k) {
    const double t = k * dt;
    const Eigen::AngleAxisd turn(WalkWorldFromBody(t - h).transpose() * WalkWorldFromBody(t + h));
    const Eigen::Vector3d omega = turn.angle() * turn.axis() / (2 * h);
    ImuSample sample;
    sample.timestamp_ns = static_cast<timestamp_ns_t>(std::llround(t * 1e9));
    for (int a = 0; a < 3; ++a) {
      sample.gyro[a] = omega[a] + kGyroBias[a] + random.Normal(0, noise.GyroSampleStddev());
    }
    sample.accel = Eigen::Vector3d(0, 0, kStandardGravity);
    imu.push_back(sample);
  }
  return imu;
}

// Frames at 10 Hz over [0.5, duration - 0.5] s whose rotations carry
// `noise_rad` of white noise (the images' error), and, within
// [drift_begin_s, drift_end_s], an extra turn about the vertical growing at
// `drift_rad_per_s` (a stretch held by a drifting VIO alone, not supported).
std::vector<GyroFrame> MakeFrames(double duration_s, const SensorRig& rig, double noise_rad,
                                  double drift_begin_s, double drift_end_s, double drift_rad_per_s,
                                  uint64_t seed) {
  Random random(seed);
  std::vector<GyroFrame> frames;
  const Eigen::Matrix3d cam_from_body = rig.cam_from_body().rotation.toRotationMatrix();
  for (int k = 5; k * 0.1 <= duration_s - 0.5; ++k) {
    const double t = k * 0.1;
    const double drift =
        drift_rad_per_s * (std::clamp(t, drift_begin_s, drift_end_s) - drift_begin_s);
    const Eigen::Vector3d noise(random.Normal(0, noise_rad), random.Normal(0, noise_rad),
                                random.Normal(0, noise_rad));
    const Eigen::Matrix3d world_from_body =
        Eigen::AngleAxisd(drift, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
        WalkWorldFromBody(t) * QuaternionExp(noise).toRotationMatrix();
    GyroFrame frame;
    frame.image_id = static_cast<image_t>(k);
    frame.timestamp_ns = static_cast<timestamp_ns_t>(std::llround(t * 1e9));
    frame.cam_from_world = Rigid3d(Eigen::Quaterniond(cam_from_body * world_from_body.transpose()),
                                   Eigen::Vector3d::Zero());
    frame.supported = !(t > drift_begin_s && t < drift_end_s);
    frames.push_back(frame);
  }
  return frames;
}

// The true cam2_from_cam1 rotation of two frames.
Eigen::Matrix3d TrueCam2FromCam1(const SensorRig& rig, double t1, double t2) {
  const Eigen::Matrix3d cam_from_body = rig.cam_from_body().rotation.toRotationMatrix();
  return cam_from_body * WalkWorldFromBody(t2).transpose() * WalkWorldFromBody(t1) *
         cam_from_body.transpose();
}

TEST(GyroPriors, BiasAndRotationsAgreeWithTheTruthWithinTheirCovariance) {
  const SensorRig rig = CameraAlongXRig();
  const std::vector<ImuSample> imu = MakeGyro(60.0, rig.imu_noise, 1);
  // Frames whose rotations are as good as the gyro's over 0.1 s.
  const std::vector<GyroFrame> frames = MakeFrames(60.0, rig, 0.00003, 0.0, 0.0, 0.0, 2);
  GyroPriorOptions options;
  options.rotation_floor_rad = 0.0;
  const GyroPriors gyro = MakeGyroPriors(frames, imu, rig, options);
  ASSERT_EQ(gyro.priors.size(), frames.size() - 1) << gyro.message;
  ASSERT_EQ(gyro.gyro_biases.size(), 3u);
  // 20 s of gyro noise: the bias to 1.7e-4 / sqrt(20 s) = 3.8e-5 rad/s per
  // axis (6.6e-5 over three axes).
  for (const Eigen::Vector3d& bias : gyro.gyro_biases) {
    EXPECT_LT((bias - kGyroBias).norm(), 1.5e-4) << bias.transpose();
  }
  // The frames agree with the priors about as their covariance says (no
  // floor here: the frames' own 0.03 mrad shows): hardly inflated.
  EXPECT_LT(gyro.sigma_factor, 1.5) << gyro.message;
  // Each prior against the true relative rotation, whitened: about unit
  // variance per axis (the covariance is neither far too tight nor far too
  // loose).
  double sum_squares = 0.0;
  for (size_t k = 0; k < gyro.priors.size(); ++k) {
    const RelativePosePrior& prior = gyro.priors[k];
    EXPECT_TRUE(prior.from_gyro);
    EXPECT_TRUE(prior.rotation_only);
    EXPECT_EQ(prior.image_id1, frames[k].image_id);
    EXPECT_EQ(prior.image_id2, frames[k + 1].image_id);
    const Eigen::Matrix3d truth =
        TrueCam2FromCam1(rig, frames[k].timestamp_ns * 1e-9, frames[k + 1].timestamp_ns * 1e-9);
    const Eigen::Vector3d error =
        QuaternionLog(Eigen::Quaterniond(truth * prior.cam2_from_cam1.rotation.conjugate()));
    sum_squares += (prior.sqrt_information->topLeftCorner<3, 3>() * error).squaredNorm();
  }
  const double variance_per_axis = sum_squares / (3.0 * static_cast<double>(gyro.priors.size()));
  std::cout << "whitened variance per axis " << variance_per_axis << "\n";
  EXPECT_GT(variance_per_axis, 0.3);
  EXPECT_LT(variance_per_axis, 3.0);
}

TEST(GyroPriors, InflatedWhereTheFramesDisagreeBeyondTheirCovariance) {
  // Frames whose rotations are 0.5 mrad off each (or a rig whose timing
  // the gyro model misses: the same disagreement) against priors of about
  // 0.2 mrad: the sigmas grow by the median's excess.
  const SensorRig rig = CameraAlongXRig();
  const std::vector<ImuSample> imu = MakeGyro(30.0, rig.imu_noise, 5);
  const GyroPriors agreeing =
      MakeGyroPriors(MakeFrames(30.0, rig, 0.00003, 0.0, 0.0, 0.0, 6), imu, rig, {});
  const GyroPriors disagreeing =
      MakeGyroPriors(MakeFrames(30.0, rig, 0.0005, 0.0, 0.0, 0.0, 6), imu, rig, {});
  std::cout << agreeing.message << "\n" << disagreeing.message << "\n";
  EXPECT_EQ(agreeing.sigma_factor, 1.0);
  // 0.5 mrad a frame: 0.7 mrad per axis between two frames, 3.5 sigmas.
  EXPECT_GT(disagreeing.sigma_factor, 2.0);
  EXPECT_NEAR(disagreeing.sigma_factor, disagreeing.median_whitened_residual / 1.5382, 1e-9);
  // A later adjustment keeps the first one's inflation as a floor: frames
  // that now agree with the gyro (pulled toward it) do not tighten the
  // priors below it, and the priors are the agreeing ones' divided by it.
  const GyroPriors floored = MakeGyroPriors(MakeFrames(30.0, rig, 0.00003, 0.0, 0.0, 0.0, 6), imu,
                                            rig, {}, disagreeing.sigma_factor);
  EXPECT_EQ(floored.sigma_factor, disagreeing.sigma_factor);
  ASSERT_EQ(floored.priors.size(), agreeing.priors.size());
  EXPECT_TRUE(floored.priors[0].sqrt_information->isApprox(
      *agreeing.priors[0].sqrt_information / disagreeing.sigma_factor, 1e-12));
  // Disagreeing more than the floor: the measured factor.
  EXPECT_EQ(MakeGyroPriors(MakeFrames(30.0, rig, 0.0005, 0.0, 0.0, 0.0, 6), imu, rig, {}, 1.5)
                .sigma_factor,
            disagreeing.sigma_factor);
}

TEST(GyroPriors, HoldTheRotationAcrossAStretchTheImagesDoNotSupport) {
  // 8 s without images in the middle of a 40 s walk, where the frames turn
  // with a drifting VIO (2 mrad/s, 16 mrad across the stretch). The priors
  // chained across the stretch give its true relative rotation, the bias
  // taken from the supported frames on either side.
  const SensorRig rig = CameraAlongXRig();
  const std::vector<ImuSample> imu = MakeGyro(40.0, rig.imu_noise, 3);
  const std::vector<GyroFrame> frames = MakeFrames(40.0, rig, 0.0005, 16.0, 24.0, 0.002, 4);
  GyroPriorOptions options;
  options.bias_window_s = 40.0;  // one bias, as the stretch lies in one window
  const GyroPriors gyro = MakeGyroPriors(frames, imu, rig, options);
  ASSERT_EQ(gyro.priors.size(), frames.size() - 1) << gyro.message;
  size_t first = 0;
  size_t last = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    if (frames[k].timestamp_ns <= 15'000'000'000) first = k;
    if (frames[k].timestamp_ns <= 25'000'000'000) last = k;
  }
  Eigen::Matrix3d chained = Eigen::Matrix3d::Identity();
  for (size_t k = first; k < last; ++k) {
    chained = gyro.priors[k].cam2_from_cam1.rotation.toRotationMatrix() * chained;
  }
  const double t1 = frames[first].timestamp_ns * 1e-9;
  const double t2 = frames[last].timestamp_ns * 1e-9;
  const Eigen::Matrix3d truth = TrueCam2FromCam1(rig, t1, t2);
  const Eigen::Matrix3d frames_cam2_from_cam1 =
      (frames[last].cam_from_world.rotation * frames[first].cam_from_world.rotation.conjugate())
          .toRotationMatrix();
  const double frames_error =
      QuaternionLog(Eigen::Quaterniond(truth * frames_cam2_from_cam1.transpose())).norm();
  const double gyro_error = QuaternionLog(Eigen::Quaterniond(truth * chained.transpose())).norm();
  std::cout << "across the stretch: frames " << frames_error << " rad, gyro " << gyro_error
            << " rad\n";
  EXPECT_GT(frames_error, 0.015);  // the drift the frames carry
  // The gyro's white noise over 10 s (0.5 mrad) and the bias's error.
  EXPECT_LT(gyro_error, 0.0015) << "frames " << frames_error;
  // The drifting frames were kept out of the bias fit: with them the bias
  // would be off by the drift's rate over the stretch's share of the window.
  EXPECT_LT((gyro.gyro_biases[0] - kGyroBias).norm(), 1e-4) << gyro.gyro_biases[0].transpose();
}

}  // namespace
}  // namespace viosfm

#include "viosfm/vio/static_init.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "viosfm/geometry/lie.h"
#include "viosfm/io/euroc.h"
#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

TEST(StaticInit, OptionsValidate) {
  EXPECT_TRUE(StaticInitOptions().Check());
  StaticInitOptions options;
  options.step_s = 2.0;
  EXPECT_NE(options.Validate().find("step_s"), std::string::npos);
  options = StaticInitOptions();
  options.max_accel_stddev = 0.0;
  EXPECT_NE(options.Validate().find("max_accel_stddev"), std::string::npos);
}

// An IMU gap (1.5 s without samples) in a static start ends it before it:
// nothing is known of the body while the IMU was silent. A gap inside the
// first window leaves no static start.
TEST(StaticInit, AnImuGapEndsTheStaticStart) {
  WalkOptions walk;
  walk.duration_s = 6.0;
  walk.static_start_s = 4.0;
  walk.seed = 21;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  const timestamp_ns_t start = trajectory.start_ns();
  const SynthesizedImu imu =
      SynthesizeImu(trajectory, start, trajectory.end_ns(), ImuSynthesisOptions());
  for (const double gap_from_s : {2.0, 0.3}) {
    std::vector<ImuSample> samples;
    for (const ImuSample& sample : imu.samples) {
      const double t_s = NsToSeconds(sample.timestamp_ns - start);
      if (t_s < gap_from_s || t_s > gap_from_s + 1.5) samples.push_back(sample);
    }
    const StaticInitResult result =
        DetectStaticStart(samples, start, trajectory.end_ns(), StaticInitOptions());
    std::cout << "IMU gap from " << gap_from_s << " s: " << StaticInitStatusName(result.status)
              << ", " << result.message << "\n";
    if (gap_from_s < 1.0) {
      EXPECT_FALSE(result.is_static());
      EXPECT_NE(result.message.find("gap"), std::string::npos) << result.message;
      continue;
    }
    ASSERT_TRUE(result.is_static()) << result.message;
    EXPECT_EQ(result.start_ns, start);
    EXPECT_LE(NsToSeconds(result.end_ns - start), gap_from_s);
    EXPECT_GT(NsToSeconds(result.end_ns - start), 0.5);
  }
}

TEST(StaticInit, GravityAlignedRotationMapsUpToZ) {
  for (const Eigen::Vector3d& up : {Eigen::Vector3d(0.3, -0.2, 0.9),
                                    Eigen::Vector3d(-0.5, 0.7, -0.2), Eigen::Vector3d(0, 0, 1)}) {
    double roll = 0;
    double pitch = 0;
    const Eigen::Quaterniond rotation = GravityAlignedRotation(up, &roll, &pitch);
    EXPECT_LT((rotation * up.normalized() - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    // Zero yaw: the rotation is Ry(pitch) Rx(roll).
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
    EXPECT_LT(rotation.angularDistance(expected), 1e-12);
  }
}

// A simulated start: 2 s static, then a walk. The body frame of the IMU is
// tilted (a fixed rotation applied to the readings) so that roll and pitch
// are not zero. Noisy readings, known biases.
TEST(StaticInit, SimulatedStaticStart) {
  WalkOptions walk;
  walk.duration_s = 6.0;
  walk.static_start_s = 2.0;
  walk.seed = 21;
  const BodyTrajectory trajectory = GenerateWalk(walk);
  ImuSynthesisOptions synthesis;  // EuRoC noise, with bias random walks
  synthesis.initial_gyro_bias = Eigen::Vector3d(0.01, -0.02, 0.03);
  synthesis.initial_accel_bias = Eigen::Vector3d(0.1, -0.05, 0.15);
  synthesis.seed = 3;
  const timestamp_ns_t start = trajectory.start_ns();
  SynthesizedImu imu = SynthesizeImu(trajectory, start, trajectory.end_ns(), synthesis);

  // imu_from_sim_body: readings in a tilted IMU frame.
  const Eigen::Quaterniond sim_body_from_imu = So3Exp(Eigen::Vector3d(0.4, -0.3, 0.7));
  for (ImuSample& sample : imu.samples) {
    sample.gyro = sim_body_from_imu.conjugate() * sample.gyro;
    sample.accel = sim_body_from_imu.conjugate() * sample.accel;
  }
  const Eigen::Vector3d true_gyro_bias =
      sim_body_from_imu.conjugate() * imu.GyroBiasAt(start + SecondsToNs(1.0));
  const Eigen::Vector3d true_accel_bias =
      sim_body_from_imu.conjugate() * imu.AccelBiasAt(start + SecondsToNs(1.0));
  const Eigen::Quaterniond world_from_imu =
      trajectory.WorldFromBody(start).rotation * sim_body_from_imu;
  const Eigen::Vector3d true_up = world_from_imu.conjugate() * Eigen::Vector3d::UnitZ();

  const StaticInitResult result =
      DetectStaticStart(imu.samples, start, trajectory.end_ns(), StaticInitOptions());
  ASSERT_TRUE(result.is_static()) << result.message;
  const double end_s = NsToSeconds(result.end_ns - start);
  const double gyro_error = (result.gyro_bias - true_gyro_bias).cwiseAbs().maxCoeff();
  const double up_error = AngleBetween(result.up_in_body, true_up);
  // What the accelerometer alone can tell: the tilt by the perpendicular bias.
  const Eigen::Vector3d biased_up = (kStandardGravity * true_up + true_accel_bias).normalized();
  const Eigen::Vector3d true_bias_along_up = true_accel_bias.dot(true_up) * true_up;
  std::cout << "simulated: static interval " << NsToSeconds(result.start_ns - start) << " .. "
            << end_s << " s (truth 0 .. 2 s), " << result.message << "\n"
            << "  gyro bias estimate " << result.gyro_bias.transpose() << ", truth "
            << true_gyro_bias.transpose() << ", max error " << gyro_error << " rad/s\n"
            << "  up direction error " << up_error * kRadToDeg << " deg (accel bias tilt "
            << AngleBetween(biased_up, true_up) * kRadToDeg << " deg), vs biased up "
            << AngleBetween(result.up_in_body, biased_up) * kRadToDeg << " deg\n"
            << "  accel bias along up " << result.accel_bias.transpose() << ", truth "
            << true_bias_along_up.transpose() << "\n";
  EXPECT_EQ(result.start_ns, start);
  // The motion starts smoothly at 2 s; the interval ends before it, after
  // dropping the motion margin (0.5 s).
  EXPECT_GT(end_s, 1.4);
  EXPECT_LE(end_s, 2.0);
  // Noise: 0.0024 rad/s per sample over ~400 samples, plus the bias walk.
  EXPECT_LT(gyro_error, 5e-4);
  EXPECT_LT(up_error * kRadToDeg, 1.0);
  EXPECT_LT(AngleBetween(result.up_in_body, biased_up), 1e-3);
  EXPECT_LT((result.accel_bias - true_bias_along_up).norm(), 0.01);
  // world_from_body maps the measured up to world z with zero yaw.
  EXPECT_LT((result.world_from_body * result.up_in_body - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_LT((result.gravity_in_body + kStandardGravity * result.up_in_body).norm(), 1e-12);

  // Starting in the motion: not static.
  const StaticInitResult moving =
      DetectStaticStart(imu.samples, start + SecondsToNs(3.0), trajectory.end_ns());
  EXPECT_EQ(moving.status, StaticInitStatus::kNotStatic) << moving.message;
  // Less than a window of data.
  const StaticInitResult short_range =
      DetectStaticStart(imu.samples, start, start + SecondsToNs(0.5));
  EXPECT_EQ(short_range.status, StaticInitStatus::kNotEnoughData);
  EXPECT_STREQ(StaticInitStatusName(short_range.status), "not enough IMU data");
}

// The first 4.7 s of EuRoC V1_01_easy: the platform stands still.
TEST(StaticInit, EurocStaticStart) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence sequence = ReadEurocDataset(root);
  ASSERT_FALSE(sequence.images.empty());
  ASSERT_TRUE(sequence.has_ground_truth());
  const timestamp_ns_t from = sequence.images.front().timestamp_ns;
  const timestamp_ns_t to = sequence.images.back().timestamp_ns;
  const StaticInitResult result = DetectStaticStart(sequence.imu, from, to);
  ASSERT_TRUE(result.is_static()) << result.message;
  const timestamp_ns_t period_ns = SecondsToNs(1.0 / sequence.rig.imu_noise.rate_hz);
  // The whole image span is static.
  EXPECT_LE(result.start_ns - from, period_ns);
  EXPECT_LE(to - result.end_ns, period_ns);

  // Ground truth over the same span: mean gyro bias, up direction.
  Eigen::Vector3d true_gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d true_accel_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d true_up = Eigen::Vector3d::Zero();
  int count = 0;
  for (const GroundTruthState& state : sequence.ground_truth) {
    if (state.timestamp_ns < from - 1000 || state.timestamp_ns > to + 1000) continue;
    ASSERT_TRUE(state.has_velocity_and_biases);
    true_gyro_bias += state.gyro_bias;
    true_accel_bias += state.accel_bias;
    true_up += state.world_from_body.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    ++count;
  }
  ASSERT_GT(count, 90);
  true_gyro_bias /= count;
  true_accel_bias /= count;
  true_up.normalize();
  double true_roll = 0;
  double true_pitch = 0;
  GravityAlignedRotation(true_up, &true_roll, &true_pitch);

  const Eigen::Vector3d gyro_error = result.gyro_bias - true_gyro_bias;
  const double up_error = AngleBetween(result.up_in_body, true_up);
  std::cout << "EuRoC V1_01 static start: " << NsToSeconds(result.end_ns - result.start_ns)
            << " s static of " << NsToSeconds(to - from) << " s; " << result.message << "\n"
            << "  gyro bias estimate " << result.gyro_bias.transpose() << " rad/s\n"
            << "  gyro bias truth    " << true_gyro_bias.transpose() << " rad/s\n"
            << "  difference         " << gyro_error.transpose() << " rad/s\n"
            << "  roll/pitch estimate " << result.roll_rad * kRadToDeg << " "
            << result.pitch_rad * kRadToDeg << " deg, truth " << true_roll * kRadToDeg << " "
            << true_pitch * kRadToDeg << " deg; up direction error " << up_error * kRadToDeg
            << " deg\n"
            << "  accel bias along up: estimate " << result.accel_bias.dot(result.up_in_body)
            << " m/s^2, truth " << true_accel_bias.dot(true_up) << " m/s^2 (truth bias "
            << true_accel_bias.transpose() << ")\n";
  EXPECT_LT(gyro_error.cwiseAbs().maxCoeff(), 2e-3);
  EXPECT_LT(up_error * kRadToDeg, 1.0);
  // Pitch is about -68 deg here, where roll is ill-conditioned: a tilt error
  // e moves the roll by up to e / cos(pitch). Roll scaled by cos(pitch) is
  // its share of the tilt.
  EXPECT_LT(std::abs(result.pitch_rad - true_pitch) * kRadToDeg, 1.0);
  EXPECT_LT(std::abs(result.roll_rad - true_roll) * std::cos(true_pitch) * kRadToDeg, 1.0);
}

}  // namespace
}  // namespace viosfm

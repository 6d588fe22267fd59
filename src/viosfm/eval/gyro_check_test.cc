#include "viosfm/eval/gyro_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "viosfm/eval/report.h"
#include "viosfm/geometry/lie.h"
#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;

constexpr double kDegToRad = M_PI / 180.0;
constexpr timestamp_ns_t kSecond = 1'000'000'000;

// The body's angular velocity (rad/s, body axes): a smooth wander of up to
// about 30 degrees a second.
Eigen::Vector3d AngularVelocity(double t) {
  return {0.3 * std::sin(t), 0.2 * std::cos(0.7 * t), 0.1 + 0.15 * std::sin(1.3 * t)};
}

struct Recording {
  SensorRig rig;
  std::vector<ImuSample> imu;  // on the IMU's clock
  Trajectory world_from_cam;   // on the camera's clock, 10 Hz
};

// world_from_body integrated in steps of 0.1 ms from the identity at IMU
// time 0; the gyro sampled at 200 Hz with `gyro_bias` added; cameras every
// 0.1 s from 0.5 s to `duration_s` - 0.5 s on the camera's clock, which is
// `offset_s` behind the IMU's (t_imu = t_cam + offset).
Recording MakeRecording(double duration_s, const Eigen::Vector3d& gyro_bias, double offset_s) {
  Recording recording;
  recording.rig.body_from_cam = Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d(1, 1, 0).normalized())),
      Eigen::Vector3d(0.02, -0.01, 0.005));
  recording.rig.cam_time_offset_ns = static_cast<timestamp_ns_t>(std::llround(offset_s * 1e9));
  const timestamp_ns_t step_ns = 100'000;
  const auto duration_ns = static_cast<timestamp_ns_t>(duration_s * 1e9);
  Eigen::Quaterniond world_from_body = Eigen::Quaterniond::Identity();
  timestamp_ns_t next_camera_ns = recording.rig.CamToImuTime(kSecond / 2);
  for (timestamp_ns_t t = 0; t <= duration_ns; t += step_ns) {
    const double seconds = static_cast<double>(t) * 1e-9;
    if (t % 5'000'000 == 0) {
      recording.imu.push_back({t, AngularVelocity(seconds) + gyro_bias, Eigen::Vector3d::Zero()});
    }
    if (t == next_camera_ns && t + kSecond / 2 <= duration_ns) {
      const Rigid3d world_from_body_pose(world_from_body, Eigen::Vector3d(seconds, 0, 0));
      recording.world_from_cam.poses.push_back(
          {t - recording.rig.cam_time_offset_ns,
           world_from_body_pose * recording.rig.body_from_cam});
      next_camera_ns += kSecond / 10;
    }
    const Eigen::Vector3d mid =
        AngularVelocity(seconds + 0.5 * static_cast<double>(step_ns) * 1e-9);
    world_from_body =
        (world_from_body * So3Exp(mid * static_cast<double>(step_ns) * 1e-9)).normalized();
  }
  return recording;
}

TEST(GyroCheck, ExactRotationsAgreeAndTheBiasIsFound) {
  const Eigen::Vector3d bias(0.01, -0.02, 0.005);
  const Recording recording = MakeRecording(12.0, bias, 0.0);
  const GyroCheckResult fitted =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, {});
  EXPECT_EQ(fitted.num_frames, recording.world_from_cam.size());
  EXPECT_EQ(fitted.intervals.size(), 11u);  // 0.5 s to 11.5 s, 1 s each
  EXPECT_EQ(fitted.num_without_imu, 0u);
  EXPECT_TRUE(fitted.bias_fitted);
  EXPECT_LT((fitted.gyro_bias - bias).norm(), 1e-4);
  EXPECT_LT(fitted.error_deg.max, 0.01);
  // The raw gyro: each second off by about the bias's turn in a second.
  GyroCheckOptions raw;
  raw.fit_bias = false;
  const GyroCheckResult unfitted =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, raw);
  EXPECT_EQ(unfitted.gyro_bias, Eigen::Vector3d::Zero());
  EXPECT_NEAR(unfitted.error_deg.median, bias.norm() / kDegToRad, 0.15 * bias.norm() / kDegToRad);
}

// A trajectory bent by 3 degrees at 6.05 s (every later camera turned about
// the world's x axis, as a reconstruction that folds there would be): only
// the interval across the bend is off, by the bend.
TEST(GyroCheck, ABendShowsInTheIntervalAcrossIt) {
  Recording recording = MakeRecording(12.0, Eigen::Vector3d(0.003, 0.0, -0.002), 0.0);
  const Eigen::Quaterniond bend(Eigen::AngleAxisd(3.0 * kDegToRad, Eigen::Vector3d::UnitX()));
  for (StampedPose& pose : recording.world_from_cam.poses) {
    if (pose.timestamp_ns >= 6 * kSecond + kSecond / 20) {
      pose.world_from_frame = Rigid3d(bend, Eigen::Vector3d::Zero()) * pose.world_from_frame;
    }
  }
  const GyroCheckResult result =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, {});
  ASSERT_EQ(result.intervals.size(), 11u);
  EXPECT_EQ(result.num_bias_intervals, 10u);  // the bend left out
  for (const GyroCheckInterval& interval : result.intervals) {
    const bool across = interval.from_ns < 6 * kSecond && interval.to_ns > 6 * kSecond;
    if (across) {
      EXPECT_NEAR(interval.error_deg, 3.0, 0.05);
    } else {
      EXPECT_LT(interval.error_deg, 0.05) << "interval from " << interval.from_ns;
    }
  }
  EXPECT_THAT(FormatGyroCheck(result, 1), HasSubstr("5.00 to 6.00 s: off by"));
}

// The camera's clock 40 ms behind the IMU's: checked at that offset the
// rotations agree; at zero they do not (the gyro's turn over the wrong
// stretch of time).
TEST(GyroCheck, TheTimeOffsetIsApplied) {
  Recording recording = MakeRecording(12.0, Eigen::Vector3d::Zero(), 0.04);
  GyroCheckOptions raw;
  raw.fit_bias = false;
  const GyroCheckResult at_offset =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, raw);
  EXPECT_LT(at_offset.error_deg.max, 0.01);
  EXPECT_EQ(at_offset.time_offset_ns, 40'000'000);
  EXPECT_THAT(FormatGyroCheck(at_offset), HasSubstr("camera-IMU time offset 40.0 ms"));
  recording.rig.cam_time_offset_ns = 0;
  const GyroCheckResult at_zero =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, raw);
  EXPECT_GT(at_zero.error_deg.rmse, 0.3);
}

TEST(GyroCheck, IntervalsOutsideTheImuOrAcrossGapsAreCountedNotCompared) {
  Recording recording = MakeRecording(12.0, Eigen::Vector3d::Zero(), 0.0);
  // The IMU ends at 8 s; the frames between 3 and 6 s are gone.
  while (recording.imu.back().timestamp_ns > 8 * kSecond) recording.imu.pop_back();
  std::vector<StampedPose> kept;
  for (const StampedPose& pose : recording.world_from_cam.poses) {
    if (pose.timestamp_ns < 3 * kSecond || pose.timestamp_ns > 6 * kSecond) kept.push_back(pose);
  }
  recording.world_from_cam.poses = kept;
  const GyroCheckResult result =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, {});
  // 0.5-1.5, 1.5-2.5 compared; 2.5-6.1 a gap; 6.1-7.1 compared; 7.1-8.1 and
  // on beyond the IMU.
  EXPECT_EQ(result.intervals.size(), 3u);
  EXPECT_EQ(result.num_gaps, 1u);
  EXPECT_EQ(result.num_without_imu, 4u);
  EXPECT_LT(result.error_deg.max, 0.01);
  const nlohmann::json json = nlohmann::json::parse(GyroCheckToJson(result, {}));
  EXPECT_EQ(json["num_intervals"], 3);
  EXPECT_EQ(json["num_gaps"], 1);
  EXPECT_EQ(json["time_offset_ns"], 0);
  EXPECT_EQ(json["intervals"].size(), 3u);
  EXPECT_EQ(json["intervals"][0]["from_ns"], result.intervals[0].from_ns);
}

// The IMU silent for 50 ms at 3.2 s: the interval across the dropout is
// not compared (its rotation would be a guess); the others are.
TEST(GyroCheck, AnIntervalAcrossAnImuDropoutIsNotCompared) {
  Recording recording = MakeRecording(6.0, Eigen::Vector3d::Zero(), 0.0);
  std::vector<ImuSample> kept;
  for (const ImuSample& sample : recording.imu) {
    if (sample.timestamp_ns <= 3'200'000'000 || sample.timestamp_ns >= 3'250'000'000) {
      kept.push_back(sample);
    }
  }
  recording.imu = kept;
  const GyroCheckResult result =
      CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, {});
  // 0.5-1.5, 1.5-2.5, 3.5-4.5, 4.5-5.5 compared; 2.5-3.5 not.
  EXPECT_EQ(result.intervals.size(), 4u);
  EXPECT_EQ(result.num_without_imu, 1u);
  EXPECT_LT(result.error_deg.max, 0.01);
}

TEST(GyroCheck, BadInputIsRefusedWithWhatWasWrong) {
  Recording recording = MakeRecording(4.0, Eigen::Vector3d::Zero(), 0.0);
  GyroCheckOptions bad;
  bad.interval_s = 0.0;
  EXPECT_THAT(
      [&] {
        CheckRotationsAgainstGyro(recording.world_from_cam, recording.imu, recording.rig, bad);
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("interval_s must be > 0")));
  Trajectory indices = recording.world_from_cam;
  indices.has_timestamps = false;
  EXPECT_THAT([&] { CheckRotationsAgainstGyro(indices, recording.imu, recording.rig, {}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("no timestamps")));
  Trajectory later = recording.world_from_cam;
  for (StampedPose& pose : later.poses) pose.timestamp_ns += 100 * kSecond;
  EXPECT_THAT([&] { CheckRotationsAgainstGyro(later, recording.imu, recording.rig, {}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("within the IMU's samples")));
}

}  // namespace
}  // namespace viosfm

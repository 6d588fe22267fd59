#include "viosfm/vio/rolling_shutter.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <iostream>
#include <random>
#include <vector>

namespace viosfm {
namespace {

// A camera (pinhole, f = 458 px, 752 x 480, no distortion) turning at a
// constant rate in its own frame and moving at a constant velocity, and
// the world points it sees. Observations are made as a rolling shutter
// makes them: each point at the time of the row it lands on.
struct Motion {
  Eigen::Vector3d cam_angular_rate;  // rad/s, camera frame
  Eigen::Vector3d velocity;          // m/s, world frame
};

constexpr double kFocal = 458.0;
constexpr int kWidth = 752;
constexpr int kHeight = 480;

Eigen::Vector2d ProjectAt(const Motion& motion, const Eigen::Vector3d& point, double t) {
  const Eigen::Matrix3d world_from_cam_rotation =
      Eigen::AngleAxisd(motion.cam_angular_rate.norm() * t, motion.cam_angular_rate.normalized())
          .toRotationMatrix();
  const Eigen::Vector3d position = motion.velocity * t;
  return (world_from_cam_rotation.transpose() * (point - position)).hnormalized();
}

double Row(const Eigen::Vector2d& normalized) {
  return kFocal * normalized.y() + 0.5 * kHeight;
}

// The observation of `point` in the frame stamped t: the row time solved
// by fixed-point iteration.
Eigen::Vector2d RollingShutterObservation(const Motion& motion, const Eigen::Vector3d& point,
                                          double t, double readout_s) {
  double time = t;
  Eigen::Vector2d normalized = ProjectAt(motion, point, time);
  for (int i = 0; i < 20; ++i) {
    time = t + RowTimeOffset(Row(normalized), kHeight, readout_s);
    normalized = ProjectAt(motion, point, time);
  }
  return normalized;
}

std::vector<Eigen::Vector3d> Points() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-0.7, 0.7), y(-0.45, 0.45), depth(2.0, 6.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 200; ++i) {
    const double z = depth(rng);
    points.emplace_back(x(rng) * z, y(rng) * z, z);
  }
  return points;
}

FrameFeatures Frame(const Motion& motion, const std::vector<Eigen::Vector3d>& points, double t,
                    double readout_s) {
  FrameFeatures frame;
  frame.timestamp_ns = static_cast<timestamp_ns_t>(t * 1e9);
  for (size_t i = 0; i < points.size(); ++i) {
    FeatureObservation observation;
    observation.track_id = i;
    observation.normalized = RollingShutterObservation(motion, points[i], t, readout_s);
    observation.pixel = kFocal * observation.normalized + Eigen::Vector2d(376.0, 240.0);
    frame.observations.push_back(observation);
  }
  return frame;
}

// Median distance (pixels) of the frame's observations from the global
// shutter's projections at its stamp.
double MedianErrorPx(const Motion& motion, const std::vector<Eigen::Vector3d>& points,
                     const FrameFeatures& frame) {
  std::vector<double> errors;
  const double t = 1e-9 * static_cast<double>(frame.timestamp_ns);
  for (const FeatureObservation& observation : frame.observations) {
    errors.push_back(
        kFocal *
        (observation.normalized - ProjectAt(motion, points[observation.track_id], t)).norm());
  }
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

constexpr double kReadout = 0.03;
constexpr double kFrameTime = 0.05;  // 20 Hz

TEST(RollingShutter, RowTimeOffsetIsCentredOnTheMiddleRow) {
  EXPECT_NEAR(RowTimeOffset(-0.5, 480, 0.03), -0.015, 1e-12);
  EXPECT_NEAR(RowTimeOffset(239.5, 480, 0.03), 0.0, 1e-12);
  EXPECT_NEAR(RowTimeOffset(479.5, 480, 0.03), 0.015, 1e-12);
}

// New corners (no previous frame): the gyro's rotation undoes a pure
// rotation exactly.
TEST(RollingShutter, GyroRotationUndoesAPureRotation) {
  const Motion motion{Eigen::Vector3d(0.4, 1.2, -0.3), Eigen::Vector3d::Zero()};
  const std::vector<Eigen::Vector3d> points = Points();
  FrameFeatures frame = Frame(motion, points, kFrameTime, kReadout);
  const double before = MedianErrorPx(motion, points, frame);
  CorrectRollingShutter(nullptr, kReadout, kHeight, motion.cam_angular_rate, &frame);
  const double after = MedianErrorPx(motion, points, frame);
  std::cout << "pure rotation, new corners: " << before << " -> " << after << " px\n";
  EXPECT_GT(before, 2.0);
  EXPECT_LT(after, 1e-6);
  // The other direction of rotation makes it worse: the sign is checked.
  FrameFeatures wrong = Frame(motion, points, kFrameTime, kReadout);
  CorrectRollingShutter(nullptr, kReadout, kHeight, -motion.cam_angular_rate, &wrong);
  EXPECT_GT(MedianErrorPx(motion, points, wrong), 1.5 * before);
}

// Tracked corners: their image velocity between two frames follows the
// rotation and the translation.
TEST(RollingShutter, ImageVelocityUndoesRotationAndTranslation) {
  const Motion motion{Eigen::Vector3d(0.4, 1.2, -0.3), Eigen::Vector3d(0.6, -0.2, 0.9)};
  const std::vector<Eigen::Vector3d> points = Points();
  const FrameFeatures previous = Frame(motion, points, 0.0, kReadout);
  FrameFeatures frame = Frame(motion, points, kFrameTime, kReadout);
  const double before = MedianErrorPx(motion, points, frame);
  CorrectRollingShutter(&previous, kReadout, kHeight, motion.cam_angular_rate, &frame);
  const double after = MedianErrorPx(motion, points, frame);
  std::cout << "rotation and translation, tracked corners: " << before << " -> " << after
            << " px\n";
  EXPECT_GT(before, 2.0);
  EXPECT_LT(after, 0.05 * before);
  // New corners get the rotation only: better, not exact.
  FrameFeatures alone = Frame(motion, points, kFrameTime, kReadout);
  CorrectRollingShutter(nullptr, kReadout, kHeight, motion.cam_angular_rate, &alone);
  const double rotation_only = MedianErrorPx(motion, points, alone);
  std::cout << "rotation and translation, new corners: " << before << " -> " << rotation_only
            << " px\n";
  EXPECT_LT(rotation_only, 0.7 * before);
}

TEST(RollingShutter, GlobalShutterIsLeftAlone) {
  const Motion motion{Eigen::Vector3d(0.4, 1.2, -0.3), Eigen::Vector3d(0.6, -0.2, 0.9)};
  const std::vector<Eigen::Vector3d> points = Points();
  const FrameFeatures previous = Frame(motion, points, 0.0, 0.0);
  FrameFeatures frame = Frame(motion, points, kFrameTime, 0.0);
  const FrameFeatures copy = frame;
  CorrectRollingShutter(&previous, 0.0, kHeight, motion.cam_angular_rate, &frame);
  for (size_t i = 0; i < frame.observations.size(); ++i) {
    EXPECT_EQ(frame.observations[i].normalized, copy.observations[i].normalized);
  }
  EXPECT_LT(MedianErrorPx(motion, points, frame), 1e-9);
}

}  // namespace
}  // namespace viosfm

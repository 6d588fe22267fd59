#include "viosfm/pipeline/all_frame_poses.h"

#include <gtest/gtest.h>

#include <cmath>

namespace viosfm {
namespace {

constexpr timestamp_ns_t kStepNs = 50'000'000;  // images at 20 Hz

// The true world_from_body at t: a walk around a circle of 3 m, turning.
Rigid3d TruePose(double t) {
  const double angle = 0.3 * t;
  const Eigen::Vector3d position(3.0 * std::cos(angle), 3.0 * std::sin(angle), 0.2 * t);
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(angle + 0.5, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.1 * std::sin(t), Eigen::Vector3d::UnitX()));
  return Rigid3d(rotation, position);
}

// A VIO that drifts: its world turns by 2 mrad/s about the vertical and
// slides by 1 cm/s, plus a segment's own world frame.
Rigid3d VioPose(double t, const Rigid3d& vio_world_from_world) {
  const Rigid3d drift(Eigen::Quaterniond(Eigen::AngleAxisd(0.002 * t, Eigen::Vector3d::UnitZ())),
                      Eigen::Vector3d(0.01 * t, -0.005 * t, 0.002 * t));
  return vio_world_from_world * drift * TruePose(t);
}

double Seconds(timestamp_ns_t t) {
  return static_cast<double>(t) * 1e-9;
}

double PositionError(const Rigid3d& a, const Rigid3d& b) {
  return (a.translation - b.translation).norm();
}

double RotationError(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation);
}

TEST(PoseAllFrames, ModelFramesKeptAndTheOthersFollowTheTruthNotTheVioDrift) {
  // 200 images (10 s); the model holds every fourth (5 Hz) at its true pose,
  // from image 20 to image 180: the ends are left out as a static trim would.
  std::vector<timestamp_ns_t> stamps;
  Trajectory vio;
  std::vector<int> segments;
  for (int i = 0; i < 200; ++i) {
    stamps.push_back(i * kStepNs);
    vio.poses.push_back({i * kStepNs, VioPose(Seconds(i * kStepNs), Rigid3d())});
    segments.push_back(0);
  }
  std::vector<ModelFramePose> model;
  for (int i = 20; i <= 180; i += 4) {
    model.push_back({stamps[i], TruePose(Seconds(stamps[i])), static_cast<size_t>(i)});
  }
  const AllFramePoses poses = PoseAllFrames(stamps, model, vio, segments, 1'000'000);
  EXPECT_EQ(poses.counts.num_images, 200u);
  EXPECT_EQ(poses.counts.num_from_model, model.size());
  EXPECT_EQ(poses.counts.num_between, 160u - 40u);
  EXPECT_EQ(poses.counts.num_beyond, 20u + 19u);
  EXPECT_EQ(poses.counts.num_unposed(), 0u);
  ASSERT_EQ(poses.world_from_body.size(), 200u);

  double max_between_m = 0.0, max_between_rad = 0.0, max_vio_step_error_m = 0.0;
  for (size_t k = 0; k < poses.world_from_body.size(); ++k) {
    const StampedPose& pose = poses.world_from_body.poses[k];
    const double t = Seconds(pose.timestamp_ns);
    const Rigid3d truth = TruePose(t);
    switch (poses.source[k]) {
      case AllFramePoseSource::kModel:
        EXPECT_LT(PositionError(pose.world_from_frame, truth), 1e-12);
        break;
      case AllFramePoseSource::kBetween:
        max_between_m = std::max(max_between_m, PositionError(pose.world_from_frame, truth));
        max_between_rad = std::max(max_between_rad, RotationError(pose.world_from_frame, truth));
        break;
      case AllFramePoseSource::kBeyond: {
        // One side only: off by the VIO's drift since the nearest model
        // frame (at most 1 s away here: 2 mrad of yaw at up to 3.4 m from
        // the vertical axis, and 1.1 cm of slide).
        const double gap_s = t < 1.0 ? 1.0 - t : t - 9.0;
        EXPECT_LT(PositionError(pose.world_from_frame, truth), gap_s * (0.002 * 3.4 + 0.0115))
            << "t = " << t;
        EXPECT_LT(RotationError(pose.world_from_frame, truth), gap_s * 0.002 + 1e-9);
        break;
      }
    }
    // What the VIO alone says of the step from the previous image, against
    // the truth: the drift of 50 ms.
    if (k > 0) {
      const Rigid3d truth_step = TruePose(t - 0.05).Inverse() * truth;
      const Rigid3d vio_step = VioPose(t - 0.05, Rigid3d()).Inverse() * VioPose(t, Rigid3d());
      max_vio_step_error_m = std::max(max_vio_step_error_m, PositionError(truth_step, vio_step));
    }
  }
  // Between two model frames 0.2 s apart the drift is linear in time and
  // the blend takes it out: what is left is second order.
  EXPECT_LT(max_between_m, 2e-5);
  EXPECT_LT(max_between_rad, 1e-6);
  // The VIO's own error over one step is larger than that: the test's
  // drift is not vacuous.
  EXPECT_GT(max_vio_step_error_m, 2e-4);
}

TEST(PoseAllFrames, SegmentsAreNotJoinedAndUnposedImagesCounted) {
  // Two VIO segments in different worlds (a re-initialisation at image 50,
  // no pose for images 48 and 49), and a third segment (images 80 to 99)
  // without any model frame.
  const Rigid3d second_world(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())),
                             Eigen::Vector3d(5.0, -2.0, 1.0));
  std::vector<timestamp_ns_t> stamps;
  Trajectory vio;
  std::vector<int> segments;
  for (int i = 0; i < 100; ++i) {
    stamps.push_back(i * kStepNs);
    if (i == 48 || i == 49) continue;
    const int segment = i < 48 ? 0 : (i < 80 ? 1 : 2);
    vio.poses.push_back(
        {i * kStepNs, VioPose(Seconds(i * kStepNs), segment == 0 ? Rigid3d() : second_world)});
    segments.push_back(segment);
  }
  const auto vio_index_of = [](int i) { return static_cast<size_t>(i < 48 ? i : i - 2); };
  std::vector<ModelFramePose> model;
  for (const int i : {0, 10, 20, 30, 40, 52, 60, 70}) {
    model.push_back({stamps[i], TruePose(Seconds(stamps[i])), vio_index_of(i)});
  }
  // A frame registered from the images alone: in the model, but no anchor.
  model.push_back({stamps[75], TruePose(Seconds(stamps[75])), std::nullopt});

  const AllFramePoses poses = PoseAllFrames(stamps, model, vio, segments, 1'000'000);
  EXPECT_EQ(poses.counts.num_from_model, 9u);
  EXPECT_EQ(poses.counts.num_without_vio_pose, 2u);      // images 48, 49
  EXPECT_EQ(poses.counts.num_without_model_frame, 20u);  // images 80 to 99
  EXPECT_EQ(poses.counts.num_beyond, 7u + 2u + 8u);      // 41-47; 50, 51; 71-79 but 75
  EXPECT_EQ(poses.world_from_body.size(), 100u - 22u);
  for (const StampedPose& pose : poses.world_from_body.poses) {
    const double t = Seconds(pose.timestamp_ns);
    // Every pose is in the model's world, whichever VIO world it came from:
    // within the drift of at most 0.45 s from a model frame.
    EXPECT_LT(PositionError(pose.world_from_frame, TruePose(t)), 0.45 * (0.002 * 3.4 + 0.0115))
        << "t = " << t;
  }
  EXPECT_NE(poses.counts.ToString().find("100 images: 9 from the model"), std::string::npos)
      << poses.counts.ToString();
}

}  // namespace
}  // namespace viosfm

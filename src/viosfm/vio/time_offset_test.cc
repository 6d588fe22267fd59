#include "viosfm/vio/time_offset.h"

#include <gtest/gtest.h>

#include <map>

#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/scene_model.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// `room` without images (motion, IMU and geometry only), 8 s at 20 Hz with
// the images stamped `camera_time_offset_s` after their true exposure times
// (viosfm simulate --camera-time-offset).
SimulatedSequence SimulateRoom(double camera_time_offset_s) {
  SimulationOptions options;
  options.duration_s = 8.0;
  options.render_images = false;
  options.camera_time_offset_s = camera_time_offset_s;
  return SimulateSequence(options);
}

// What a tracker would hand over for each image: 1500 points scattered over
// the room's surfaces (a fixed seed), each seen where it is visible from
// the camera at the image's true exposure time, with 0.05 px of noise (the
// residual the estimate leaves on rendered room sequences is 0.02 px); the
// point's index is its track id. Frames are stamped with the image stamps.
std::vector<FrameFeatures> TrackedFrames(const SimulatedSequence& simulated) {
  const Scene& scene = simulated.scenario->scene;
  const Camera& camera = simulated.sequence.rig.camera;
  Random random(5);
  std::vector<Eigen::Vector3d> points_in_world;
  for (int i = 0; i < 1500; ++i) {
    const TexturedQuad& quad =
        scene.quads()[random.UniformInt(0, static_cast<int64_t>(scene.quads().size()) - 1)];
    points_in_world.push_back(quad.origin + random.Uniform() * quad.axis_u +
                              random.Uniform() * quad.axis_v);
  }
  const double focal_px = camera.params[0];
  std::map<uint64_t, int> track_lengths;
  std::vector<FrameFeatures> frames;
  for (size_t k = 0; k < simulated.sequence.images.size(); ++k) {
    const Rigid3d cam_from_world = SimulatedCamFromWorld(simulated, simulated.FrameTime(k));
    const Eigen::Vector3d centre = cam_from_world.Inverse().translation;
    std::map<uint64_t, int> seen;
    FrameFeatures frame;
    frame.timestamp_ns = simulated.sequence.images[k].timestamp_ns;
    for (size_t i = 0; i < points_in_world.size(); ++i) {
      const Eigen::Vector3d point_in_cam = cam_from_world * points_in_world[i];
      if (point_in_cam.z() < 0.2) continue;
      const std::optional<Eigen::Vector2d> pixel = Project(camera, point_in_cam);
      if (!pixel || pixel->x() < 0 || pixel->y() < 0 || pixel->x() > camera.width - 1 ||
          pixel->y() > camera.height - 1) {
        continue;
      }
      // Hidden behind another surface (the boxes)?
      const Eigen::Vector3d ray = points_in_world[i] - centre;
      const std::optional<RayHit> hit = scene.Intersect(centre, ray.normalized());
      if (hit && hit->t < ray.norm() - 1e-3) continue;
      FeatureObservation observation;
      observation.track_id = i;
      observation.normalized = point_in_cam.hnormalized() +
                               Eigen::Vector2d(random.Normal(), random.Normal()) * 0.05 / focal_px;
      observation.pixel = CamToImage(camera, observation.normalized);
      const auto previous = track_lengths.find(i);
      observation.track_length = previous == track_lengths.end() ? 1 : previous->second + 1;
      seen[i] = observation.track_length;
      frame.observations.push_back(observation);
    }
    // A point that leaves the view is a new track when it comes back.
    track_lengths = std::move(seen);
    frames.push_back(std::move(frame));
  }
  return frames;
}

// The frames the VIO collects before estimating (odometry.cc): from the
// first, until the gyro has turned by min_total_rotation_deg at the
// calibration's offset.
std::vector<FrameFeatures> StartupFrames(const std::vector<FrameFeatures>& frames,
                                         const std::vector<ImuSample>& imu,
                                         const TimeOffsetOptions& options) {
  std::vector<FrameFeatures> startup;
  double rotation_deg = 0.0;
  for (const FrameFeatures& frame : frames) {
    startup.push_back(frame);
    if (startup.size() >= 2) {
      rotation_deg += GyroRotationSumDeg({startup[startup.size() - 2], startup.back()}, imu, 0);
    }
    if (rotation_deg >= options.min_total_rotation_deg) break;
  }
  return startup;
}

TEST(EstimateTimeOffset, RecoversTheSimulatedCameraDelay) {
  // 47 ms late: the real RealSense recording's delay (`vio-robustness.sh`'s
  // time_offset case); and 20 ms early.
  for (const double delay_s : {0.047, -0.02}) {
    const SimulatedSequence simulated = SimulateRoom(delay_s);
    const TimeOffsetOptions options;
    const std::vector<FrameFeatures> startup =
        StartupFrames(TrackedFrames(simulated), simulated.sequence.imu, options);
    ASSERT_LT(startup.size(), simulated.sequence.images.size()) << "not enough rotation";
    const TimeOffsetEstimate estimate =
        EstimateTimeOffset(startup, simulated.sequence.imu, simulated.sequence.rig.body_from_cam,
                           0, simulated.sequence.rig.camera.params[0], options);
    ASSERT_TRUE(estimate.estimated) << estimate.message;
    // t_imu = t_cam + offset: the offset is minus the delay (measured: -46.8
    // and 20.2 ms).
    EXPECT_NEAR(NsToSeconds(estimate.offset_ns), -delay_s, 0.001) << estimate.message;
    // Measured: 0.02 px against 0.07 px (47 ms) and 0.04 px (-20 ms).
    EXPECT_LT(estimate.cost_px, 0.7 * estimate.calibration_cost_px) << estimate.message;
    EXPECT_GE(estimate.total_rotation_deg, options.min_total_rotation_deg);
  }
}

TEST(EstimateTimeOffset, KeepsACalibrationThatIsRight) {
  const SimulatedSequence simulated = SimulateRoom(0.0);
  const TimeOffsetOptions options;
  const TimeOffsetEstimate estimate = EstimateTimeOffset(
      StartupFrames(TrackedFrames(simulated), simulated.sequence.imu, options),
      simulated.sequence.imu, simulated.sequence.rig.body_from_cam, 0,
      simulated.sequence.rig.camera.params[0], options);
  // The search finds no offset clearly better than the calibration's.
  EXPECT_EQ(estimate.offset_ns, 0) << estimate.message;
  EXPECT_NE(estimate.message.find("kept"), std::string::npos) << estimate.message;
}

TEST(EstimateTimeOffset, TooLittleRotationKeepsTheCalibration) {
  // The first 2 s: the static start, no rotation to measure the offset on.
  const SimulatedSequence simulated = SimulateRoom(0.047);
  std::vector<FrameFeatures> frames = TrackedFrames(simulated);
  frames.resize(40);
  const TimeOffsetEstimate estimate =
      EstimateTimeOffset(frames, simulated.sequence.imu, simulated.sequence.rig.body_from_cam, 0,
                         simulated.sequence.rig.camera.params[0]);
  EXPECT_FALSE(estimate.estimated) << estimate.message;
  EXPECT_EQ(estimate.offset_ns, 0);
  EXPECT_LT(estimate.total_rotation_deg, 1.0);
}

}  // namespace
}  // namespace viosfm

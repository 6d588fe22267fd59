#include "viosfm/vio/time_offset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"
#include "viosfm/util/timestamp.h"
#include "viosfm/vio/rolling_shutter.h"

namespace viosfm {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// A walk seen by the simulator's default camera: landmarks 2-6 m in front
// of each frame's camera, observed (with their track id) by that frame and
// the two before and after it when they project inside the image, plus
// Gaussian pixel noise; IMU at 200 Hz with EuRoC noise (zero initial bias).
// The IMU clock is the simulation's time; image k is taken at T_k and
// stamped T_k - true_offset on the camera clock, so that t_imu = t_cam +
// true_offset (time_offset.h's convention).
struct OffsetScene {
  BodyTrajectory trajectory;
  std::vector<FrameFeatures> frames;
  std::vector<timestamp_ns_t> true_stamps;  // T_k, IMU clock
  std::vector<ImuSample> imu;
  Rigid3d body_from_cam = SimulationOptions::DefaultBodyFromCam();
  double focal_length_px = 0.0;
};

struct OffsetSceneOptions {
  timestamp_ns_t true_offset_ns = 0;
  double first_frame_s = 1.0;  // s after the walk's start
  double camera_rate_hz = 20.0;
  int num_frames = 120;
  int landmarks_per_frame = 40;
  double pixel_noise_px = 0.5;
  // s, a rolling shutter's readout (0: global): each corner is seen at its
  // row's time (rolling_shutter.h's convention).
  double readout_s = 0.0;
  bool imu_noise = true;
  uint64_t seed = 0;
};

OffsetScene MakeOffsetScene(const OffsetSceneOptions& options) {
  OffsetScene scene;
  WalkOptions walk;
  walk.duration_s = options.first_frame_s + options.num_frames / options.camera_rate_hz + 1.0;
  walk.seed = options.seed;
  scene.trajectory = GenerateWalk(walk);
  const Camera camera = SimulationOptions::DefaultCamera();
  const double fx = camera.params[0];
  const double fy = camera.params[1];
  const double cx = camera.params[2];
  const double cy = camera.params[3];
  const double width = static_cast<double>(camera.width);
  const double height = static_cast<double>(camera.height);
  scene.focal_length_px = 0.5 * (fx + fy);
  Random random(options.seed + 100);

  std::vector<Rigid3d> cam_from_world;
  for (int k = 0; k < options.num_frames; ++k) {
    const timestamp_ns_t t = scene.trajectory.start_ns() +
                             SecondsToNs(options.first_frame_s + k / options.camera_rate_hz);
    scene.true_stamps.push_back(t);
    cam_from_world.push_back((scene.trajectory.WorldFromBody(t) * scene.body_from_cam).Inverse());
  }
  std::vector<Eigen::Vector3d> landmarks;
  for (int k = 0; k < options.num_frames; ++k) {
    const Rigid3d world_from_cam = cam_from_world[k].Inverse();
    for (int i = 0; i < options.landmarks_per_frame; ++i) {
      const double u = random.Uniform(0.0, width - 1.0);
      const double v = random.Uniform(0.0, height - 1.0);
      const double depth = random.Uniform(2.0, 6.0);
      landmarks.push_back(world_from_cam *
                          Eigen::Vector3d((u - cx) / fx * depth, (v - cy) / fy * depth, depth));
    }
  }
  for (int k = 0; k < options.num_frames; ++k) {
    FrameFeatures frame;
    frame.timestamp_ns = scene.true_stamps[k] - options.true_offset_ns;
    const int first = std::max(0, k - 2) * options.landmarks_per_frame;
    const int last = std::min(options.num_frames, k + 3) * options.landmarks_per_frame;
    for (int i = first; i < last; ++i) {
      Eigen::Vector3d in_cam = cam_from_world[k] * landmarks[i];
      if (in_cam.z() < 0.1) continue;
      Eigen::Vector2d pixel(fx * in_cam.x() / in_cam.z() + cx, fy * in_cam.y() / in_cam.z() + cy);
      // With a rolling shutter, the pose at the row's time; the row moves
      // with it (a few fixed-point steps converge far below a pixel).
      for (int step = 0; step < 4 && options.readout_s > 0.0; ++step) {
        const timestamp_ns_t t =
            scene.true_stamps[k] +
            SecondsToNs(RowTimeOffset(pixel.y(), camera.height, options.readout_s));
        in_cam = (scene.trajectory.WorldFromBody(t) * scene.body_from_cam).Inverse() * landmarks[i];
        if (in_cam.z() < 0.1) break;
        pixel =
            Eigen::Vector2d(fx * in_cam.x() / in_cam.z() + cx, fy * in_cam.y() / in_cam.z() + cy);
      }
      if (in_cam.z() < 0.1) continue;
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > width - 1 || pixel.y() > height - 1) {
        continue;
      }
      pixel += Eigen::Vector2d(random.Normal(0.0, options.pixel_noise_px),
                               random.Normal(0.0, options.pixel_noise_px));
      FeatureObservation observation;
      observation.track_id = static_cast<uint64_t>(i);
      observation.pixel = pixel;
      observation.normalized = Eigen::Vector2d((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
      frame.observations.push_back(observation);
    }
    scene.frames.push_back(std::move(frame));
  }
  ImuSynthesisOptions imu_options;
  imu_options.add_noise = options.imu_noise;
  imu_options.seed = options.seed + 1;
  scene.imu = SynthesizeImu(scene.trajectory, scene.trajectory.start_ns(),
                            scene.trajectory.end_ns(), imu_options)
                  .samples;
  return scene;
}

// Sum over consecutive frames of the true rotation angle between their poses (deg).
double TrueRotationSumDeg(const OffsetScene& scene, size_t num_frames) {
  double sum = 0.0;
  for (size_t k = 0; k + 1 < num_frames; ++k) {
    const Eigen::Quaterniond& a = scene.trajectory.WorldFromBody(scene.true_stamps[k]).rotation;
    const Eigen::Quaterniond& b = scene.trajectory.WorldFromBody(scene.true_stamps[k + 1]).rotation;
    sum += a.angularDistance(b);
  }
  return sum * kRadToDeg;
}

double Ms(timestamp_ns_t ns) {
  return NsToSeconds(ns) * 1e3;
}

// ms. Without pixel noise the estimate is exact (0.0 ms error); with the
// scenes' 0.5 px it scatters, the epipolar cost being flat in the offset
// because the free translation absorbs part of a rotation error: pairing
// consecutive frames only, -1.4 to +1.9 ms over six seeds at a true offset
// of 0 (+-2.5 ms at 1 px); pairing frames up to 3 apart (the default),
// -0.6 to +0.6 ms in the cases below.
constexpr double kOffsetToleranceMs = 1.5;

TEST(TimeOffset, OptionsValidate) {
  EXPECT_EQ(TimeOffsetOptions().Validate(), "");
  const auto error_of = [](auto change) {
    TimeOffsetOptions options;
    change(options);
    return options.Validate();
  };
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.max_offset_s = 0.0; }).find("max_offset_s"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.coarse_step_s = 0.2; }).find("coarse_step_s"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.coarse_step_s = 0.0; }).find("coarse_step_s"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.fine_step_s = 0.005; }).find("fine_step_s"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.fine_step_s = -1e-3; }).find("fine_step_s"),
            std::string::npos);
  EXPECT_NE(
      error_of([](TimeOffsetOptions& o) { o.min_tracks_per_pair = 4; }).find("min_tracks_per_pair"),
      std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) {
              o.min_total_rotation_deg = -1.0;
            }).find("min_total_rotation_deg"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) {
              o.target_rotation_deg = 20.0;
            }).find("target_rotation_deg"),
            std::string::npos);
  EXPECT_NE(error_of([](TimeOffsetOptions& o) { o.max_wait_s = 0.0; }).find("max_wait_s"),
            std::string::npos);
  EXPECT_NE(
      error_of([](TimeOffsetOptions& o) { o.min_cost_reduction = 1.0; }).find("min_cost_reduction"),
      std::string::npos);
  EXPECT_NE(
      error_of([](TimeOffsetOptions& o) { o.min_cost_reduction = NAN; }).find("min_cost_reduction"),
      std::string::npos);
  TimeOffsetOptions bad;
  bad.max_offset_s = -0.1;
  EXPECT_FALSE(bad.Check());
}

// The gyro's rotation summed over the frame pairs equals the true one
// (noise-free IMU), at the right offset; frames outside the IMU count zero.
TEST(TimeOffset, GyroRotationSumMatchesTheTruth) {
  OffsetSceneOptions options;
  options.true_offset_ns = SecondsToNs(0.03);
  options.imu_noise = false;
  const OffsetScene scene = MakeOffsetScene(options);
  const double truth_deg = TrueRotationSumDeg(scene, scene.frames.size());
  const double gyro_deg = GyroRotationSumDeg(scene.frames, scene.imu, options.true_offset_ns);
  std::cout << "rotation over " << scene.frames.size() << " frames: truth " << truth_deg
            << " deg, gyro " << gyro_deg << " deg\n";
  EXPECT_GT(truth_deg, 90.0);
  EXPECT_NEAR(gyro_deg, truth_deg, 1e-3 * truth_deg);
  // No IMU at all, or frames stamped long after it: zero.
  EXPECT_EQ(GyroRotationSumDeg(scene.frames, {}, options.true_offset_ns), 0.0);
  EXPECT_EQ(GyroRotationSumDeg(scene.frames, scene.imu, SecondsToNs(100.0)), 0.0);
}

// Known offsets of -30, 0 and +30 ms (calibration 0) are recovered within
// kOffsetToleranceMs, with a cost clearly below the calibration's when the
// calibration is wrong; a right calibration is kept.
TEST(TimeOffset, RecoversAKnownOffset) {
  for (const double offset_ms : {-30.0, 0.0, 30.0}) {
    for (const uint64_t seed : {0, 1}) {
      OffsetSceneOptions options;
      options.true_offset_ns = SecondsToNs(offset_ms * 1e-3);
      options.seed = seed;
      const OffsetScene scene = MakeOffsetScene(options);
      const TimeOffsetEstimate estimate = EstimateTimeOffset(
          scene.frames, scene.imu, scene.body_from_cam, 0, scene.focal_length_px);
      std::cout << "true offset " << offset_ms << " ms, seed " << seed << ": " << estimate.message
                << "\n";
      // With the right calibration (0 ms) the estimate is no better and the
      // calibration's offset is kept; otherwise the estimate replaces it.
      EXPECT_EQ(estimate.estimated, offset_ms != 0.0) << estimate.message;
      EXPECT_EQ(estimate.calibration_offset_ns, 0);
      // Frames 1 to 3 apart (the scene's corners live 5 frames).
      const int n = static_cast<int>(scene.frames.size());
      EXPECT_EQ(estimate.num_pairs, (n - 1) + (n - 2) + (n - 3));
      EXPECT_GT(estimate.total_rotation_deg, 90.0);
      EXPECT_NEAR(Ms(estimate.offset_ns), offset_ms, kOffsetToleranceMs) << estimate.message;
      if (offset_ms != 0.0) {
        // 30 ms off, the residual is 20 to 30 % above the noise floor left
        // at the estimate (the translation absorbs the rest).
        EXPECT_LT(estimate.cost_px, 0.9 * estimate.calibration_cost_px) << estimate.message;
      }
    }
  }
}

// The search is centred on the calibration's offset: a calibration of +20
// ms and a truth of -25 ms.
TEST(TimeOffset, SearchesAroundTheCalibration) {
  OffsetSceneOptions options;
  options.true_offset_ns = SecondsToNs(-0.025);
  options.seed = 2;
  const OffsetScene scene = MakeOffsetScene(options);
  const timestamp_ns_t calibration_ns = SecondsToNs(0.02);
  const TimeOffsetEstimate estimate = EstimateTimeOffset(
      scene.frames, scene.imu, scene.body_from_cam, calibration_ns, scene.focal_length_px);
  EXPECT_TRUE(estimate.estimated) << estimate.message;
  EXPECT_EQ(estimate.calibration_offset_ns, calibration_ns);
  EXPECT_NEAR(Ms(estimate.offset_ns), -25.0, kOffsetToleranceMs) << estimate.message;

  // A truth outside a +-20 ms range around the calibration: the minimum is
  // at the range's edge, not trusted; the calibration's offset stands.
  TimeOffsetOptions narrow;
  narrow.max_offset_s = 0.02;
  const TimeOffsetEstimate edge = EstimateTimeOffset(scene.frames, scene.imu, scene.body_from_cam,
                                                     calibration_ns, scene.focal_length_px, narrow);
  EXPECT_FALSE(edge.estimated) << edge.message;
  EXPECT_EQ(edge.offset_ns, calibration_ns);
  EXPECT_NE(edge.message.find("edge"), std::string::npos) << edge.message;
}

// A rolling shutter (corners seen at their rows' times): asked with the
// image height, the estimator finds the readout and the offset; the same
// scene seen by a global shutter gets no readout.
TEST(TimeOffset, EstimatesARollingShuttersReadout) {
  const int height = static_cast<int>(SimulationOptions::DefaultCamera().height);
  for (const uint64_t seed : {0, 1}) {
    OffsetSceneOptions options;
    options.true_offset_ns = SecondsToNs(-0.02);
    options.readout_s = 0.03;
    options.seed = seed;
    const OffsetScene rolling = MakeOffsetScene(options);
    const TimeOffsetEstimate estimate =
        EstimateTimeOffset(rolling.frames, rolling.imu, rolling.body_from_cam, 0,
                           rolling.focal_length_px, TimeOffsetOptions(), height);
    std::cout << "readout 30 ms, offset -20 ms, seed " << seed << ": " << estimate.message << "\n";
    EXPECT_TRUE(estimate.readout_estimated) << estimate.message;
    EXPECT_NEAR(estimate.readout_s * 1e3, 30.0, 3.0) << estimate.message;
    EXPECT_TRUE(estimate.estimated) << estimate.message;
    EXPECT_NEAR(Ms(estimate.offset_ns), -20.0, kOffsetToleranceMs) << estimate.message;
    // As a global shutter (no height given), the offset absorbs part of the
    // readout's effect and the residual stays higher.
    const TimeOffsetEstimate global = EstimateTimeOffset(
        rolling.frames, rolling.imu, rolling.body_from_cam, 0, rolling.focal_length_px);
    EXPECT_FALSE(global.readout_estimated);
    EXPECT_EQ(global.readout_s, 0.0);
    EXPECT_LT(estimate.cost_px, 0.9 * global.cost_px) << global.message;

    options.readout_s = 0.0;
    const OffsetScene global_shutter = MakeOffsetScene(options);
    const TimeOffsetEstimate none =
        EstimateTimeOffset(global_shutter.frames, global_shutter.imu, global_shutter.body_from_cam,
                           0, global_shutter.focal_length_px, TimeOffsetOptions(), height);
    std::cout << "global shutter, seed " << seed << ": " << none.message << "\n";
    EXPECT_FALSE(none.readout_estimated) << none.message;
    EXPECT_EQ(none.readout_s, 0.0);
    EXPECT_NEAR(Ms(none.offset_ns), -20.0, kOffsetToleranceMs) << none.message;
  }
}

// The least rotation the estimate is made with (30 degrees, less than the
// 90 the driver waits for): on the shortest start of the walk whose gyro
// rotation reaches 30 degrees (under 45 by the true poses), with the
// calibration 35 ms off, eight walks give the offset within 8 ms each
// (measured 0.6 to 7.0 ms) and within 4 ms on average (3.0). That is less
// precise than the whole walk's 1.5 ms (kOffsetToleranceMs), which is why
// the driver waits for 90 degrees when the motion gives them; it still
// removes more than three quarters of the calibration's error.
TEST(TimeOffset, ThirtyDegreesOfRotationAreEnough) {
  constexpr double kToleranceMs = 8.0;
  constexpr double kMeanToleranceMs = 4.0;
  constexpr int kNumWalks = 8;
  double sum_error_ms = 0.0;
  for (uint64_t seed = 0; seed < kNumWalks; ++seed) {
    OffsetSceneOptions options;
    options.true_offset_ns = SecondsToNs(0.03);
    options.seed = seed;
    const OffsetScene scene = MakeOffsetScene(options);
    const TimeOffsetOptions defaults;
    const timestamp_ns_t calibration_ns = SecondsToNs(-0.005);
    // The shortest start whose gyro rotation (as the estimate sums it, at the
    // calibration's offset) reaches the least needed.
    std::vector<FrameFeatures> frames(scene.frames.begin(), scene.frames.begin() + 2);
    while (frames.size() < scene.frames.size() &&
           GyroRotationSumDeg(frames, scene.imu, calibration_ns) <
               defaults.min_total_rotation_deg) {
      frames.push_back(scene.frames[frames.size()]);
    }
    const double truth_deg = TrueRotationSumDeg(scene, frames.size());
    ASSERT_LT(truth_deg, 45.0);
    const TimeOffsetEstimate estimate = EstimateTimeOffset(frames, scene.imu, scene.body_from_cam,
                                                           calibration_ns, scene.focal_length_px);
    std::cout << "seed " << seed << ", first " << frames.size() << " frames (" << truth_deg
              << " deg true rotation): " << estimate.message << "\n";
    ASSERT_TRUE(estimate.estimated) << estimate.message;
    EXPECT_NEAR(Ms(estimate.offset_ns), 30.0, kToleranceMs) << estimate.message;
    sum_error_ms += std::abs(Ms(estimate.offset_ns) - 30.0);
  }
  EXPECT_LT(sum_error_ms / kNumWalks, kMeanToleranceMs);
}

// Too little rotation (the first frames of the walk, 10 degrees, under the
// 30 the estimate needs): the estimate is not made and the calibration's
// offset is kept, whatever the truth. (Made anyway, it is 8 ms off here.)
TEST(TimeOffset, TooLittleRotationKeepsTheCalibration) {
  OffsetSceneOptions options;
  options.true_offset_ns = SecondsToNs(0.03);
  const OffsetScene scene = MakeOffsetScene(options);
  std::vector<FrameFeatures> frames(scene.frames.begin(), scene.frames.begin() + 12);
  const double truth_deg = TrueRotationSumDeg(scene, frames.size());
  // The test's premise, from the true poses.
  ASSERT_LT(truth_deg, TimeOffsetOptions().min_total_rotation_deg);
  const timestamp_ns_t calibration_ns = SecondsToNs(0.005);
  const TimeOffsetEstimate estimate = EstimateTimeOffset(frames, scene.imu, scene.body_from_cam,
                                                         calibration_ns, scene.focal_length_px);
  std::cout << "first " << frames.size() << " frames (" << truth_deg
            << " deg true rotation): " << estimate.message << "\n";
  EXPECT_FALSE(estimate.estimated);
  EXPECT_EQ(estimate.offset_ns, calibration_ns);
  EXPECT_NE(estimate.message.find("too little rotation"), std::string::npos) << estimate.message;

  // Too few frame pairs with enough shared corners.
  TimeOffsetOptions demanding;
  demanding.min_tracks_per_pair = 100000;
  const TimeOffsetEstimate no_pairs =
      EstimateTimeOffset(scene.frames, scene.imu, scene.body_from_cam, calibration_ns,
                         scene.focal_length_px, demanding);
  EXPECT_FALSE(no_pairs.estimated);
  EXPECT_EQ(no_pairs.num_pairs, 0);
  EXPECT_EQ(no_pairs.offset_ns, calibration_ns);
  EXPECT_NE(no_pairs.message.find("too few"), std::string::npos) << no_pairs.message;
}

}  // namespace
}  // namespace viosfm

#include "viosfm/vio/vi_initializer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "viosfm/sim/imu_synthesis.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/sim/trajectory.h"
#include "viosfm/util/random.h"
#include "viosfm/util/timestamp.h"

namespace viosfm {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

struct Scenario {
  BodyTrajectory trajectory;
  std::vector<FrameFeatures> frames;
  SynthesizedImu imu;
  Rigid3d body_from_cam = SimulationOptions::DefaultBodyFromCam();
  ImuNoise noise;
};

struct ScenarioOptions {
  int num_keyframes = 10;
  double first_keyframe_s = 1.0;    // s after the trajectory start
  double keyframe_spacing_s = 0.2;  // s
  int landmarks_per_keyframe = 60;
  double pixel_noise_px = 0.0;
  // Fraction of observations moved by 10 to 60 px in a random direction
  // (mistracked corners).
  double outlier_ratio = 0.0;
  bool imu_noise = false;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  uint64_t seed = 0;
};

// Landmarks 2-5 m in front of the keyframes' cameras, projected through the
// true poses with a pinhole of the simulator's default intrinsics (the
// features are undistorted anyway), plus Gaussian pixel noise.
Scenario MakeScenario(const BodyTrajectory& trajectory, const ScenarioOptions& options) {
  Scenario scenario;
  scenario.trajectory = trajectory;
  const Camera camera = SimulationOptions::DefaultCamera();
  const double fx = camera.params[0];
  const double fy = camera.params[1];
  const double cx = camera.params[2];
  const double cy = camera.params[3];
  const double width = static_cast<double>(camera.width);
  const double height = static_cast<double>(camera.height);
  Random random(options.seed + 100);

  std::vector<timestamp_ns_t> stamps;
  std::vector<Rigid3d> world_from_cams;
  for (int k = 0; k < options.num_keyframes; ++k) {
    const timestamp_ns_t t = trajectory.start_ns() +
                             SecondsToNs(options.first_keyframe_s + k * options.keyframe_spacing_s);
    stamps.push_back(t);
    world_from_cams.push_back(trajectory.WorldFromBody(t) * scenario.body_from_cam);
  }
  std::vector<Eigen::Vector3d> landmarks;
  for (int k = 0; k < options.num_keyframes; ++k) {
    for (int i = 0; i < options.landmarks_per_keyframe; ++i) {
      const double u = random.Uniform(0.0, width - 1.0);
      const double v = random.Uniform(0.0, height - 1.0);
      const double depth = random.Uniform(2.0, 5.0);
      const Eigen::Vector3d in_cam((u - cx) / fx * depth, (v - cy) / fy * depth, depth);
      landmarks.push_back(world_from_cams[k] * in_cam);
    }
  }
  for (int k = 0; k < options.num_keyframes; ++k) {
    FrameFeatures frame;
    frame.timestamp_ns = stamps[k];
    frame.is_keyframe = true;
    const Rigid3d cam_from_world = world_from_cams[k].Inverse();
    for (size_t i = 0; i < landmarks.size(); ++i) {
      const Eigen::Vector3d in_cam = cam_from_world * landmarks[i];
      if (in_cam.z() < 0.1) continue;
      Eigen::Vector2d pixel(fx * in_cam.x() / in_cam.z() + cx, fy * in_cam.y() / in_cam.z() + cy);
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > width - 1 || pixel.y() > height - 1) {
        continue;
      }
      pixel += Eigen::Vector2d(random.Normal(0.0, options.pixel_noise_px),
                               random.Normal(0.0, options.pixel_noise_px));
      if (options.outlier_ratio > 0.0 && random.Uniform() < options.outlier_ratio) {
        const double angle = random.Uniform(0.0, 2.0 * M_PI);
        pixel += random.Uniform(10.0, 60.0) * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      }
      FeatureObservation observation;
      observation.track_id = 1000 + i;
      observation.pixel = pixel;
      observation.normalized = Eigen::Vector2d((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
      frame.observations.push_back(observation);
    }
    scenario.frames.push_back(std::move(frame));
  }
  ImuSynthesisOptions imu_options;
  imu_options.add_noise = options.imu_noise;
  imu_options.initial_gyro_bias = options.gyro_bias;
  imu_options.seed = options.seed + 1;
  scenario.noise = imu_options.noise;
  scenario.imu = SynthesizeImu(trajectory, stamps.front() - SecondsToNs(0.1),
                               stamps.back() + SecondsToNs(0.1), imu_options);
  return scenario;
}

BodyTrajectory Walk(uint64_t seed) {
  WalkOptions walk;
  walk.duration_s = 5.0;
  walk.seed = seed;
  return GenerateWalk(walk);
}

struct Errors {
  double scale_error = 0.0;         // relative
  double gravity_error_deg = 0.0;   // gravity direction in the first body frame
  double max_velocity_error = 0.0;  // m/s, in the first body frame
  double max_position_error = 0.0;  // m, relative to the first body, in its frame
};

// Compares with the truth in gauge-free terms: everything expressed in the
// first keyframe's body frame, relative to its position.
Errors Evaluate(const Scenario& scenario, const ViInitResult& result) {
  Errors errors;
  const Rigid3d true_world_from_b0 =
      scenario.trajectory.WorldFromBody(result.states.front().timestamp_ns);
  const Rigid3d& est_world_from_b0 = result.states.front().world_from_body;
  const Eigen::Vector3d true_last =
      true_world_from_b0.Inverse() *
      scenario.trajectory.PositionInWorld(result.states.back().timestamp_ns);
  const Eigen::Vector3d est_last =
      est_world_from_b0.Inverse() * result.states.back().world_from_body.translation;
  errors.scale_error = std::abs(est_last.norm() / true_last.norm() - 1.0);
  errors.gravity_error_deg =
      AngleBetween(true_world_from_b0.rotation.inverse() * -Eigen::Vector3d::UnitZ(),
                   est_world_from_b0.rotation.inverse() * -Eigen::Vector3d::UnitZ()) *
      kRadToDeg;
  for (const ImuState& state : result.states) {
    const Eigen::Vector3d true_v = true_world_from_b0.rotation.inverse() *
                                   scenario.trajectory.VelocityInWorld(state.timestamp_ns);
    const Eigen::Vector3d est_v = est_world_from_b0.rotation.inverse() * state.velocity_in_world;
    errors.max_velocity_error = std::max(errors.max_velocity_error, (true_v - est_v).norm());
    const Eigen::Vector3d true_p =
        true_world_from_b0.Inverse() * scenario.trajectory.PositionInWorld(state.timestamp_ns);
    const Eigen::Vector3d est_p = est_world_from_b0.Inverse() * state.world_from_body.translation;
    errors.max_position_error = std::max(errors.max_position_error, (true_p - est_p).norm());
  }
  return errors;
}

ViInitResult RunInit(const Scenario& scenario, const ViInitOptions& options = {}) {
  return InitializeVisualInertial(scenario.frames, scenario.imu.samples, scenario.body_from_cam,
                                  scenario.noise, options);
}

TEST(ViInitializer, OptionsValidate) {
  EXPECT_TRUE(ViInitOptions().Check());
  ViInitOptions options;
  options.window_size = 2;
  EXPECT_NE(options.Validate().find("window_size"), std::string::npos);
  options = ViInitOptions();
  options.max_baseline_m = 0.01;
  EXPECT_NE(options.Validate().find("max_baseline_m"), std::string::npos);
  options = ViInitOptions();
  options.focal_length_px = 0.0;
  EXPECT_NE(options.Validate().find("focal_length_px"), std::string::npos);
}

TEST(ViInitializer, NoiseFreeRecoversScaleGravityVelocityAndGyroBias) {
  const Eigen::Vector3d gyro_bias(0.01, -0.02, 0.015);
  for (uint64_t seed = 0; seed < 3; ++seed) {
    ScenarioOptions options;
    options.seed = seed;
    options.gyro_bias = gyro_bias;
    const Scenario scenario = MakeScenario(Walk(seed), options);
    const ViInitResult result = RunInit(scenario);
    ASSERT_TRUE(result.success) << result.message;
    ASSERT_EQ(result.states.size(), scenario.frames.size());
    const Errors errors = Evaluate(scenario, result);
    std::cout << "noise-free seed " << seed << ": scale error " << errors.scale_error
              << ", gravity " << errors.gravity_error_deg << " deg, velocity "
              << errors.max_velocity_error << " m/s, position " << errors.max_position_error
              << " m, gyro bias error " << (result.gyro_bias - gyro_bias).norm()
              << " rad/s, accel std " << result.accel_stddev << ", |g| linear "
              << result.gravity_norm_linear << "\n";
    EXPECT_LT(errors.scale_error, 0.01);
    EXPECT_LT(errors.gravity_error_deg, 0.5);
    EXPECT_LT(errors.max_velocity_error, 0.02);
    EXPECT_LT((result.gyro_bias - gyro_bias).norm(), 1e-3);
    EXPECT_LT(errors.max_position_error, 0.02);
    // World conventions: gravity along -z, origin and zero yaw at the first body.
    EXPECT_LT((result.gravity_in_world - Eigen::Vector3d(0, 0, -kStandardGravity)).norm(), 1e-12);
    EXPECT_LT(result.states.front().world_from_body.translation.norm(), 1e-12);
    const Eigen::Vector3d x_axis =
        result.states.front().world_from_body.rotation * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(x_axis.y(), x_axis.x()), 0.0, 1e-9);
    // Landmarks: metric, reproject onto their observations in every keyframe.
    ASSERT_GT(result.points_in_world.size(), 100u);
    const Rigid3d cam_from_body = scenario.body_from_cam.Inverse();
    double max_error = 0.0;
    for (size_t k = 0; k < scenario.frames.size(); ++k) {
      const Rigid3d cam_from_world = cam_from_body * result.states[k].world_from_body.Inverse();
      for (const FeatureObservation& observation : scenario.frames[k].observations) {
        const auto it = result.points_in_world.find(observation.track_id);
        if (it == result.points_in_world.end()) continue;
        const Eigen::Vector3d in_cam = cam_from_world * it->second;
        max_error = std::max(max_error, (in_cam.hnormalized() - observation.normalized).norm());
      }
    }
    EXPECT_LT(max_error * 458.0, 0.5) << "max reprojection error, px";
  }
}

TEST(ViInitializer, RealisticNoise) {
  const Eigen::Vector3d gyro_bias(-0.004, 0.006, 0.003);
  double worst_scale = 0.0;
  double worst_gravity = 0.0;
  double worst_velocity = 0.0;
  double worst_gyro_bias = 0.0;
  for (uint64_t seed = 0; seed < 5; ++seed) {
    ScenarioOptions options;
    options.seed = seed;
    options.gyro_bias = gyro_bias;
    options.imu_noise = true;
    options.pixel_noise_px = 0.5;
    const Scenario scenario = MakeScenario(Walk(seed + 10), options);
    const ViInitResult result = RunInit(scenario);
    ASSERT_TRUE(result.success) << result.message;
    const Errors errors = Evaluate(scenario, result);
    const double bias_error = (result.gyro_bias - scenario.imu.gyro_bias.front()).norm();
    std::cout << "noisy seed " << seed << ": scale error " << errors.scale_error << ", gravity "
              << errors.gravity_error_deg << " deg, velocity " << errors.max_velocity_error
              << " m/s, gyro bias error " << bias_error << " rad/s, reprojection RMS "
              << result.reprojection_rms_px << " px, accel std " << result.accel_stddev
              << ", |g| linear " << result.gravity_norm_linear << "\n";
    worst_scale = std::max(worst_scale, errors.scale_error);
    worst_gravity = std::max(worst_gravity, errors.gravity_error_deg);
    worst_velocity = std::max(worst_velocity, errors.max_velocity_error);
    worst_gyro_bias = std::max(worst_gyro_bias, bias_error);
  }
  std::cout << "noisy worst: scale " << worst_scale << ", gravity " << worst_gravity
            << " deg, velocity " << worst_velocity << " m/s, gyro bias " << worst_gyro_bias
            << " rad/s\n";
  EXPECT_LT(worst_scale, 0.05);
  EXPECT_LT(worst_gravity, 2.0);
  EXPECT_LT(worst_velocity, 0.1);
  EXPECT_LT(worst_gyro_bias, 2e-3);
}

TEST(ViInitializer, OutliersAndLongerInput) {
  // 14 keyframes given: the last 10 (window_size) are used.
  ScenarioOptions options;
  options.num_keyframes = 14;
  options.seed = 5;
  options.gyro_bias = Eigen::Vector3d(0.003, 0.002, -0.005);
  options.imu_noise = true;
  options.pixel_noise_px = 0.5;
  options.outlier_ratio = 0.05;
  const Scenario scenario = MakeScenario(Walk(21), options);
  const ViInitResult result = RunInit(scenario);
  ASSERT_TRUE(result.success) << result.message;
  ASSERT_EQ(result.states.size(), 10u);
  for (size_t k = 0; k < 10; ++k) {
    EXPECT_EQ(result.states[k].timestamp_ns, scenario.frames[k + 4].timestamp_ns);
  }
  const Errors errors = Evaluate(scenario, result);
  std::cout << "5% outliers: scale error " << errors.scale_error << ", gravity "
            << errors.gravity_error_deg << " deg, velocity " << errors.max_velocity_error
            << " m/s, reprojection RMS " << result.reprojection_rms_px << " px, "
            << result.points_in_world.size() << " landmarks\n";
  EXPECT_LT(errors.scale_error, 0.05);
  EXPECT_LT(errors.gravity_error_deg, 2.0);
  EXPECT_LT(result.reprojection_rms_px, 1.0);
}

TEST(ViInitializer, StaticStartFails) {
  WalkOptions walk;
  walk.duration_s = 6.0;
  walk.static_start_s = 5.0;
  ScenarioOptions options;
  options.pixel_noise_px = 0.5;
  options.imu_noise = true;
  const Scenario scenario = MakeScenario(GenerateWalk(walk), options);
  const ViInitResult result = RunInit(scenario);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("parallax"), std::string::npos) << result.message;
  EXPECT_TRUE(result.states.empty());
}

// A body whose position follows a uniform B-spline with the given control
// points and whose attitude wanders (yaw +-0.3 rad, pitch/roll +-0.1 rad).
BodyTrajectory MakeTrajectory(const std::vector<Eigen::Vector3d>& positions) {
  std::vector<Eigen::Vector3d> angles;
  for (size_t i = 0; i < positions.size(); ++i) {
    const double phase = static_cast<double>(i);
    angles.emplace_back(0.3 * std::sin(1.3 * phase), 0.1 * std::sin(0.7 * phase + 1.0),
                        0.1 * std::cos(0.9 * phase));
  }
  return BodyTrajectory(1'000'000'000'000'000'000, CubicBSpline<3>(0.0, 0.5, positions),
                        CubicBSpline<3>(0.0, 0.5, angles));
}

TEST(ViInitializer, PureRotationFails) {
  const std::vector<Eigen::Vector3d> positions(14, Eigen::Vector3d(0.0, 0.0, 1.4));
  ScenarioOptions options;
  options.pixel_noise_px = 0.5;
  options.imu_noise = true;
  const Scenario scenario = MakeScenario(MakeTrajectory(positions), options);
  const ViInitResult result = RunInit(scenario);
  EXPECT_FALSE(result.success);
  EXPECT_TRUE(result.message.find("parallax") != std::string::npos ||
              result.message.find("excitation") != std::string::npos)
      << result.message;
  std::cout << "pure rotation: " << result.message << "\n";
}

TEST(ViInitializer, ConstantVelocityFailsForLackOfExcitation) {
  // Control points on a line, equally spaced: exactly constant velocity
  // (0.8 m/s forward), while the attitude still changes.
  std::vector<Eigen::Vector3d> positions;
  for (int i = 0; i < 14; ++i) positions.emplace_back(0.4 * i, 0.0, 1.4);
  ScenarioOptions options;
  options.pixel_noise_px = 0.5;
  options.imu_noise = true;
  const Scenario scenario = MakeScenario(MakeTrajectory(positions), options);
  const ViInitResult result = RunInit(scenario);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("excitation"), std::string::npos) << result.message;
  std::cout << "constant velocity: " << result.message << "\n";
}

// Small motions make the scale weakly observable: the initialiser must
// either fail or be right, never succeed with a wrong scale or gravity.
TEST(ViInitializer, SmallMotionNeverGivesWrongSuccess) {
  int num_failed = 0;
  for (const double amplitude : {0.005, 0.02, 0.08}) {
    std::vector<Eigen::Vector3d> positions;
    for (int i = 0; i < 14; ++i) {
      positions.push_back(Eigen::Vector3d(0.0, 0.0, 1.4) +
                          amplitude * Eigen::Vector3d(std::sin(1.1 * i), std::cos(0.8 * i),
                                                      std::sin(1.7 * i + 0.5)));
    }
    ScenarioOptions options;
    options.seed = 3;
    options.imu_noise = true;
    options.pixel_noise_px = 0.5;
    const Scenario scenario = MakeScenario(MakeTrajectory(positions), options);
    const ViInitResult result = RunInit(scenario);
    if (!result.success) {
      ++num_failed;
      std::cout << "amplitude " << amplitude << " m: failed: " << result.message << "\n";
      continue;
    }
    const Errors errors = Evaluate(scenario, result);
    std::cout << "amplitude " << amplitude << " m: scale error " << errors.scale_error
              << ", gravity " << errors.gravity_error_deg << " deg, accel std "
              << result.accel_stddev << " m/s^2, parallax " << result.median_parallax_deg
              << " deg\n";
    EXPECT_LT(errors.scale_error, 0.1) << "amplitude " << amplitude;
    EXPECT_LT(errors.gravity_error_deg, 3.0) << "amplitude " << amplitude;
  }
  // The smallest motion (a few millimetres) must not pass.
  EXPECT_GE(num_failed, 1);
}

TEST(ViInitializer, TooFewFramesOrMissingImuFail) {
  ScenarioOptions options;
  const Scenario scenario = MakeScenario(Walk(3), options);
  std::vector<FrameFeatures> few(scenario.frames.begin(), scenario.frames.begin() + 3);
  ViInitResult result =
      InitializeVisualInertial(few, scenario.imu.samples, scenario.body_from_cam, scenario.noise);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("too few keyframes"), std::string::npos) << result.message;
  std::vector<ImuSample> short_imu(scenario.imu.samples.begin(),
                                   scenario.imu.samples.begin() + 100);
  result =
      InitializeVisualInertial(scenario.frames, short_imu, scenario.body_from_cam, scenario.noise);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("IMU"), std::string::npos) << result.message;
}

TEST(ViInitializer, Deterministic) {
  ScenarioOptions options;
  options.pixel_noise_px = 0.5;
  options.imu_noise = true;
  options.seed = 7;
  const Scenario scenario = MakeScenario(Walk(7), options);
  const ViInitResult a = RunInit(scenario);
  const ViInitResult b = RunInit(scenario);
  ASSERT_TRUE(a.success) << a.message;
  ASSERT_TRUE(b.success);
  EXPECT_EQ(a.scale, b.scale);
  ASSERT_EQ(a.states.size(), b.states.size());
  for (size_t k = 0; k < a.states.size(); ++k) {
    EXPECT_EQ(a.states[k].world_from_body.translation, b.states[k].world_from_body.translation);
    EXPECT_EQ(a.states[k].velocity_in_world, b.states[k].velocity_in_world);
  }
  EXPECT_EQ(a.points_in_world.size(), b.points_in_world.size());
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sim/sequence_simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/io/scene_structure_io.h"
#include "viosfm/io/trajectory_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

SimulationOptions ShortOptions() {
  SimulationOptions options;
  options.duration_s = 10.0;
  options.static_start_s = 1.0;
  options.seed = 5;
  options.render_images = false;  // motion and IMU only (images: scenarios_test)
  return options;
}

TEST(SequenceSimulator, ProducesConsistentStreams) {
  const SimulationOptions options = ShortOptions();
  const SimulatedSequence simulated = SimulateSequence(options);
  const Sequence& sequence = simulated.sequence;
  EXPECT_EQ(sequence.images.size(), 201u);  // 10 s at 20 Hz, both ends
  EXPECT_EQ(sequence.imu.size(), 2001u);    // 10 s at 200 Hz
  ASSERT_EQ(sequence.ground_truth.size(), sequence.images.size());
  ASSERT_EQ(simulated.vio_body.size(), sequence.images.size());
  // During the static start the specific force is gravity plus bias and noise.
  const Eigen::Vector3d f = sequence.imu[10].accel - sequence.ground_truth[0].accel_bias;
  EXPECT_NEAR(f.norm(), kStandardGravity, 6 * options.imu.noise.AccelSampleStddev());
  // The default camera looks forward: the body's x axis is the camera's z axis.
  EXPECT_LT(
      (options.body_from_cam.rotation * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(),
      1e-12);
}

TEST(SequenceSimulator, WritesAReadableDataset) {
  const SimulationOptions options = ShortOptions();
  const SimulatedSequence simulated = SimulateSequence(options);
  const fs::path out = testing::MakeScratchFolder("simulate");
  WriteSimulatedSequence(out, simulated, options);
  const std::vector<ImuSample> imu = ReadEurocImu(out / "mav0/imu0/data.csv");
  ASSERT_EQ(imu.size(), simulated.sequence.imu.size());
  EXPECT_EQ(imu.back().accel, simulated.sequence.imu.back().accel);
  const auto gt = ReadEurocGroundTruth(out / "mav0/state_groundtruth_estimate0/data.csv");
  ASSERT_EQ(gt.size(), simulated.sequence.ground_truth.size());
  EXPECT_EQ(gt[50].velocity_in_world, simulated.sequence.ground_truth[50].velocity_in_world);
  const auto calibration = ReadEurocCameraYaml(out / "mav0/cam0/sensor.yaml");
  EXPECT_EQ(calibration.camera.params, options.camera.params);
  const Trajectory vio = ReadTumTrajectory(out / "vio_emulated.tum");
  ASSERT_EQ(vio.size(), simulated.vio_body.size());
  EXPECT_EQ(vio.poses[7].timestamp_ns, simulated.vio_body.poses[7].timestamp_ns);
  EXPECT_LT((vio.poses[7].world_from_frame.translation -
             simulated.vio_body.poses[7].world_from_frame.translation)
                .norm(),
            1e-9);
}

TEST(SequenceSimulator, WritesTheSceneStructure) {
  SimulationOptions options = ShortOptions();
  options.scenario = "two_floors";
  options.duration_s = 2.0;
  const SimulatedSequence simulated = SimulateSequence(options);
  const fs::path out = testing::MakeScratchFolder("simulate_structure");
  WriteSimulatedSequence(out, simulated, options);
  const SceneStructure read = ReadSceneStructure(out / "scene.csv");
  const Scene& scene = simulated.scenario->scene;
  ASSERT_EQ(read.size(), scene.quads().size());
  int per_floor[2] = {0, 0};
  for (size_t k = 0; k < read.size(); ++k) {
    const TexturedQuad& quad = scene.quads()[k];
    EXPECT_EQ(read[k].id, static_cast<int>(k));
    EXPECT_EQ(read[k].texture_id, quad.texture_id);
    EXPECT_EQ(read[k].origin, quad.origin);
    EXPECT_EQ(read[k].axis_u, quad.axis_u);
    EXPECT_EQ(read[k].axis_v, quad.axis_v);
    const Eigen::Vector3d center = quad.origin + 0.5 * (quad.axis_u + quad.axis_v);
    const int region = simulated.scenario->RegionIndex(center);
    EXPECT_EQ(read[k].region, region >= 0 ? simulated.scenario->regions[region].name : "none");
    if (read[k].floor >= 0) ++per_floor[read[k].floor];
  }
  // The two floors have the same layout: as many quads each.
  EXPECT_GT(per_floor[0], 40);
  EXPECT_EQ(per_floor[0], per_floor[1]);
}

TEST(SequenceSimulator, IsReproducibleAndRejectsUnknownScenarios) {
  const SimulatedSequence a = SimulateSequence(ShortOptions());
  const SimulatedSequence b = SimulateSequence(ShortOptions());
  EXPECT_EQ(a.sequence.imu.back().gyro, b.sequence.imu.back().gyro);
  EXPECT_EQ(a.vio_body.poses.back().world_from_frame.translation,
            b.vio_body.poses.back().world_from_frame.translation);
  SimulationOptions options = ShortOptions();
  options.scenario = "moon";
  try {
    SimulateSequence(options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "scenario 'moon' is unknown (available: room, two_floors, corridor, dark, mav)"),
              std::string::npos);
  }
}

// A tiny rendered sequence: 2 s (0.5 s static) at 5 Hz, 47 x 30 pixels.
SimulationOptions TinyRenderedOptions() {
  SimulationOptions options;
  options.duration_s = 2.0;
  options.static_start_s = 0.5;
  options.camera_rate_hz = 5.0;
  options.texels_per_metre = 16.0;
  options.seed = 4;
  options.num_threads = 1;
  Camera& camera = options.camera;
  camera.width = 47;
  camera.height = 30;
  camera.params = {28.7, 28.6, 23.0, 15.0, 0, 0, 0, 0};
  return options;
}

std::string FileBytes(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << stream.rdbuf();
  return bytes.str();
}

TEST(SequenceSimulator, CameraTimeOffsetShiftsTheImageStampsOnly) {
  const SimulationOptions options = TinyRenderedOptions();
  SimulationOptions shifted = options;
  shifted.camera_time_offset_s = 0.047;
  const fs::path out_a = testing::MakeScratchFolder("simulate_offset_a");
  const fs::path out_b = testing::MakeScratchFolder("simulate_offset_b");
  const SimulatedSequence a = SimulateSequence(options);
  const SimulatedSequence b = SimulateSequence(shifted);
  WriteSimulatedSequence(out_a, a, options);
  WriteSimulatedSequence(out_b, b, shifted);
  const Sequence read_a = ReadEurocDataset(out_a);
  const Sequence read_b = ReadEurocDataset(out_b);
  ASSERT_EQ(read_a.images.size(), 11u);
  ASSERT_EQ(read_b.images.size(), read_a.images.size());
  for (size_t k = 0; k < read_a.images.size(); ++k) {
    // Stamped 47 ms late, the same picture (the pose at the true time).
    EXPECT_EQ(read_b.images[k].timestamp_ns, read_a.images[k].timestamp_ns + 47'000'000);
    EXPECT_EQ(read_b.images[k].path.filename().string(),
              std::to_string(read_a.images[k].timestamp_ns + 47'000'000) + ".png");
    EXPECT_EQ(ReadGreyImage(read_b.images[k].path).pixels,
              ReadGreyImage(read_a.images[k].path).pixels);
    EXPECT_EQ(b.FrameTime(k), a.sequence.images[k].timestamp_ns);
  }
  // The IMU, the ground truth (at the true times) and the calibration
  // (which states no offset) are unchanged, byte for byte.
  for (const char* file : {"mav0/imu0/data.csv", "mav0/imu0/sensor.yaml", "mav0/cam0/sensor.yaml",
                           "mav0/state_groundtruth_estimate0/data.csv", "vio_emulated.tum"}) {
    EXPECT_EQ(FileBytes(out_b / file), FileBytes(out_a / file)) << file;
  }
  EXPECT_EQ(read_b.rig.cam_time_offset_ns, 0);
}

TEST(SequenceSimulator, ImuNoiseFileScaleChangesTheCalibrationNotTheData) {
  SimulationOptions options = ShortOptions();
  options.duration_s = 3.0;
  options.static_start_s = 2.0;
  SimulationOptions wrong = options;
  wrong.imu_noise_file_scale_gyro = 1.0 / 13.0;
  wrong.imu_noise_file_scale_accel = 30.0;
  const fs::path out_a = testing::MakeScratchFolder("simulate_noise_a");
  const fs::path out_b = testing::MakeScratchFolder("simulate_noise_b");
  const SimulatedSequence a = SimulateSequence(options);
  const SimulatedSequence b = SimulateSequence(wrong);
  WriteSimulatedSequence(out_a, a, options);
  WriteSimulatedSequence(out_b, b, wrong);
  const ImuNoise truth = options.imu.noise;
  const ImuNoise stated = ReadEurocImuYaml(out_b / "mav0/imu0/sensor.yaml").noise;
  EXPECT_NEAR(stated.gyro_noise_density, truth.gyro_noise_density / 13.0, 1e-12);
  EXPECT_NEAR(stated.gyro_random_walk, truth.gyro_random_walk / 13.0, 1e-12);
  EXPECT_NEAR(stated.accel_noise_density, truth.accel_noise_density * 30.0, 1e-12);
  EXPECT_NEAR(stated.accel_random_walk, truth.accel_random_walk * 30.0, 1e-12);
  EXPECT_EQ(b.true_imu_noise.gyro_noise_density, truth.gyro_noise_density);
  // The data are those of the true noise: byte for byte the same file, and
  // at rest (the first 2 s, 400 samples) the spread of the gyro readings is
  // the true density times sqrt(200 Hz), not the stated one.
  EXPECT_EQ(FileBytes(out_b / "mav0/imu0/data.csv"), FileBytes(out_a / "mav0/imu0/data.csv"));
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  int count = 0;
  for (const ImuSample& sample : b.sequence.imu) {
    if (sample.timestamp_ns > b.sequence.imu.front().timestamp_ns + 1'900'000'000) break;
    sum += sample.gyro;
    sum_sq += sample.gyro.cwiseProduct(sample.gyro);
    ++count;
  }
  const Eigen::Vector3d variance = sum_sq / count - (sum / count).cwiseAbs2();
  const double measured = std::sqrt(variance.mean());
  EXPECT_NEAR(measured / truth.GyroSampleStddev(), 1.0, 0.1);  // 380 samples x 3 axes: +-4 %
}

TEST(SequenceSimulator, AutoExposureScalesTheFrameBrightnessByItsGain) {
  SimulationOptions options = TinyRenderedOptions();
  options.duration_s = 10.0;
  SimulationOptions exposed = options;
  exposed.auto_exposure.strength_stops = 1.0;
  const SimulatedSequence a = SimulateSequence(options);
  const SimulatedSequence b = SimulateSequence(exposed);
  ASSERT_EQ(b.exposure_gains.size(), b.sequence.images.size());
  // The frame whose gain differs most from 1 (at least a third of a stop
  // over 10 s with this seed).
  size_t k = 0;
  for (size_t j = 0; j < b.exposure_gains.size(); ++j) {
    if (std::abs(std::log(b.exposure_gains[j])) > std::abs(std::log(b.exposure_gains[k]))) k = j;
  }
  const double gain = b.exposure_gains[k];
  ASSERT_GT(std::abs(std::log2(gain)), 0.33);
  const RayTable rays(options.camera);
  const GreyImage plain = RenderSimulatedFrame(a, rays, k, options);
  const GreyImage scaled = RenderSimulatedFrame(b, rays, k, exposed);
  // Same sensor noise, radiance times the gain: over the pixels that do not
  // clip, the sums are in the ratio of the gain.
  double sum_plain = 0.0;
  double sum_scaled = 0.0;
  int used = 0;
  for (size_t p = 0; p < plain.pixels.size(); ++p) {
    if (plain.pixels[p] < 3 || scaled.pixels[p] < 3 || plain.pixels[p] > 252 ||
        scaled.pixels[p] > 252)
      continue;
    sum_plain += plain.pixels[p];
    sum_scaled += scaled.pixels[p];
    ++used;
  }
  ASSERT_GT(used, 1000);
  EXPECT_NEAR(sum_scaled / sum_plain, gain, 0.01 * gain);
}

TEST(SequenceSimulator, RollingShutterRowsAreThoseOfAGlobalShutterAtTheRowTimes) {
  SimulationOptions options = TinyRenderedOptions();
  options.rolling_shutter_readout_s = 0.03;
  for (const double exposure_s : {0.0, 0.01}) {
    options.exposure_time_s = exposure_s;
    const SimulatedSequence simulated = SimulateSequence(options);
    const RayTable rays(options.camera);
    const size_t k = 7;  // 1.4 s: moving
    const GreyImage rolling = RenderSimulatedFrame(simulated, rays, k, options);
    RenderOptions render = simulated.scenario->render;
    render.seed = MixSeed(options.seed, k);
    render.num_threads = 1;
    const int height = static_cast<int>(options.camera.height);
    const int width = static_cast<int>(options.camera.width);
    int differing_from_the_stamp = 0;
    for (int y = 0; y < height; ++y) {
      // Row y at t + ((y + 0.5) / 30 - 0.5) * 30 ms = t + (y - 14.5) ms.
      const timestamp_ns_t t = simulated.sequence.images[k].timestamp_ns + (2 * y - 29) * 500'000;
      const timestamp_ns_t half = 5'000'000;
      const GreyImage global =
          exposure_s > 0.0
              ? RenderWithMotionBlur(simulated.scenario->scene, rays,
                                     SimulatedCamFromWorld(simulated, t - half),
                                     SimulatedCamFromWorld(simulated, t + half), render)
              : Render(simulated.scenario->scene, rays, SimulatedCamFromWorld(simulated, t),
                       render);
      const GreyImage at_stamp = Render(
          simulated.scenario->scene, rays,
          SimulatedCamFromWorld(simulated, simulated.sequence.images[k].timestamp_ns), render);
      for (int x = 0; x < width; ++x) {
        const size_t p = static_cast<size_t>(y) * width + x;
        ASSERT_EQ(rolling.pixels[p], global.pixels[p]) << "row " << y << " column " << x;
        differing_from_the_stamp += rolling.pixels[p] != at_stamp.pixels[p];
      }
    }
    EXPECT_GT(differing_from_the_stamp, 100) << "exposure " << exposure_s;
  }
}

TEST(SequenceSimulator, WithoutImperfectionsTheOptionsFileIsUnchanged) {
  const SimulationOptions options = ShortOptions();
  const fs::path out = testing::MakeScratchFolder("simulate_yaml");
  WriteSimulatedSequence(out, SimulateSequence(options), options);
  const std::string yaml = FileBytes(out / "simulation.yaml");
  EXPECT_EQ(yaml.find("robustness"), std::string::npos);
  EXPECT_FALSE(fs::exists(out / "exposure.csv"));
  SimulationOptions exposed = options;
  exposed.auto_exposure.strength_stops = 0.5;
  exposed.camera_time_offset_s = -0.01;
  const fs::path out_b = testing::MakeScratchFolder("simulate_yaml_b");
  WriteSimulatedSequence(out_b, SimulateSequence(exposed), exposed);
  const std::string yaml_b = FileBytes(out_b / "simulation.yaml");
  EXPECT_EQ(yaml_b.substr(0, yaml.size()), yaml);
  EXPECT_NE(yaml_b.find("  camera_time_offset_s: -0.01\n"), std::string::npos);
  EXPECT_NE(yaml_b.find("    strength_stops: 0.5\n"), std::string::npos);
}

}  // namespace
}  // namespace viosfm

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Keyframe-like frames with the realistic VIO: irregular gaps within the
// bounds, ground truth and VIO on the dense grid, a re-initialisation's
// gap and segments in the written trajectory.
TEST(SequenceSimulator, KeyframesWithARealisticReinitialisingVio) {
  SimulationOptions options;
  options.scenario = "room";
  options.duration_s = 40.0;
  options.camera_rate_hz = 20.0;
  options.render_images = false;
  options.keyframes.enabled = true;
  options.vio_profile = "realistic";
  options.realistic_vio.reinit_times_s = {20.0};
  options.realistic_vio.reinit_gap_s = 1.0;
  const SimulatedSequence simulated = SimulateSequence(options);
  const Sequence& sequence = simulated.sequence;
  ASSERT_GT(sequence.images.size(), 15u);
  ASSERT_LT(sequence.images.size(), 60u);  // 40 s / 1.4 s mean gap ~ 28
  double shortest = 1e9, longest = 0.0;
  for (size_t k = 1; k < sequence.images.size(); ++k) {
    const double gap =
        static_cast<double>(sequence.images[k].timestamp_ns - sequence.images[k - 1].timestamp_ns) *
        1e-9;
    shortest = std::min(shortest, gap);
    longest = std::max(longest, gap);
  }
  EXPECT_GE(shortest, 0.05 - 1e-9);
  EXPECT_LE(longest, 7.0 + 0.05);
  EXPECT_GT(longest / shortest, 5.0);
  EXPECT_EQ(sequence.ground_truth.size(), 801u);     // the 20 Hz grid
  EXPECT_EQ(simulated.vio_body.size(), 801u - 20u);  // 1 s re-initialising
  EXPECT_EQ(simulated.vio_segments.back(), 1);
  EXPECT_EQ(simulated.frame_regions.size(), sequence.images.size());

  const fs::path folder = testing::MakeScratchFolder("sim_keyframes");
  WriteSimulatedSequence(folder, simulated, options);
  const Trajectory vio = ReadTumTrajectory(folder / "vio_emulated.tum");
  EXPECT_EQ(vio.size(), simulated.vio_body.size());
  EXPECT_EQ(SegmentsFromTimeGaps(vio, 500'000'000), simulated.vio_segments);
}

}  // namespace
}  // namespace viosfm

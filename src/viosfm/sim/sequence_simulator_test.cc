#include "viosfm/sim/sequence_simulator.h"

#include <gtest/gtest.h>

#include "viosfm/io/euroc.h"
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
                  "scenario 'moon' is unknown (available: room, two_floors, corridor, dark)"),
              std::string::npos);
  }
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
  EXPECT_EQ(sequence.ground_truth.size(), 801u);  // the 20 Hz grid
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

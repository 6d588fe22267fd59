#include "viosfm/io/euroc_writer.h"

#include <gtest/gtest.h>

#include "viosfm/io/euroc.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {
namespace fs = std::filesystem;

// Reads the real EuRoC excerpt, writes it with the writer, reads it back:
// every number must survive exactly (rotations to 1e-15 rad).
TEST(EurocWriter, RoundTripsTheRealDatasetExactly) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  const Sequence original = ReadEurocDataset(root);
  const fs::path out = testing::MakeScratchFolder("euroc_writer");
  WriteEurocDataset(out, original);
  EurocReadOptions options;
  options.check_images_exist = false;  // pixels are not copied
  const Sequence copy = ReadEurocDataset(out, options);

  ASSERT_EQ(copy.images.size(), original.images.size());
  for (size_t i = 0; i < copy.images.size(); ++i) {
    EXPECT_EQ(copy.images[i].timestamp_ns, original.images[i].timestamp_ns);
    EXPECT_EQ(copy.images[i].path.filename(), original.images[i].path.filename());
  }
  EXPECT_EQ(copy.rig.camera.model_id, original.rig.camera.model_id);
  EXPECT_EQ(copy.rig.camera.params, original.rig.camera.params);
  EXPECT_EQ(copy.rig.camera.width, original.rig.camera.width);
  EXPECT_EQ(copy.rig.body_from_cam.translation, original.rig.body_from_cam.translation);
  EXPECT_LT(copy.rig.body_from_cam.rotation.angularDistance(original.rig.body_from_cam.rotation),
            1e-15);
  EXPECT_EQ(copy.rig.camera_rate_hz, original.rig.camera_rate_hz);
  EXPECT_EQ(copy.rig.imu_noise.gyro_noise_density, original.rig.imu_noise.gyro_noise_density);
  EXPECT_EQ(copy.rig.imu_noise.accel_random_walk, original.rig.imu_noise.accel_random_walk);
  ASSERT_EQ(copy.imu.size(), original.imu.size());
  for (size_t i = 0; i < copy.imu.size(); ++i) {
    ASSERT_EQ(copy.imu[i].timestamp_ns, original.imu[i].timestamp_ns);
    ASSERT_EQ(copy.imu[i].gyro, original.imu[i].gyro);
    ASSERT_EQ(copy.imu[i].accel, original.imu[i].accel);
  }
  ASSERT_EQ(copy.ground_truth.size(), original.ground_truth.size());
  for (size_t i = 0; i < copy.ground_truth.size(); ++i) {
    const GroundTruthState& a = copy.ground_truth[i];
    const GroundTruthState& b = original.ground_truth[i];
    ASSERT_EQ(a.timestamp_ns, b.timestamp_ns);
    ASSERT_EQ(a.world_from_body.translation, b.world_from_body.translation);
    // The reader normalises quaternions, which may move the last bit again.
    ASSERT_LT(a.world_from_body.rotation.angularDistance(b.world_from_body.rotation), 1e-15);
    ASSERT_EQ(a.velocity_in_world, b.velocity_in_world);
    ASSERT_EQ(a.gyro_bias, b.gyro_bias);
    ASSERT_EQ(a.accel_bias, b.accel_bias);
  }
}

TEST(EurocWriter, RejectsCameraModelsWithoutEurocEquivalent) {
  Camera camera;
  camera.model_id = CameraModelId::kSimpleRadial;
  camera.params = {500, 320, 240, 0.1};
  const fs::path out = testing::MakeScratchFolder("euroc_writer_bad");
  EXPECT_THROW(WriteEurocCameraYaml(out / "sensor.yaml", camera, Rigid3d(), 20.0), InputError);
  EXPECT_FALSE(fs::exists(out / "sensor.yaml"));
}

}  // namespace
}  // namespace viosfm

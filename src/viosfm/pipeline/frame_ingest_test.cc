#include "viosfm/pipeline/frame_ingest.h"

#include <gtest/gtest.h>

#include <string>

#include "viosfm/scene/rolling_shutter.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

Camera TestCamera() {
  return MakeCamera(CameraModelId::kPinhole, 640, 480, {500.0, 500.0, 320.0, 240.0});
}

ImageFeatures TestFeatures() {
  ImageFeatures features;
  for (int k = 0; k < 5; ++k) {
    FeatureKeypoint keypoint;
    keypoint.x = 50.0f + 100.0f * static_cast<float>(k);
    keypoint.y = 40.0f + 90.0f * static_cast<float>(k);
    features.keypoints.push_back(keypoint);
  }
  features.descriptors = FeatureDescriptors(5, 128);
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 128; ++c) features.descriptors(r, c) = static_cast<uint8_t>(r * 7 + c);
  }
  return features;
}

SequenceImage TestImage() {
  SequenceImage image;
  image.timestamp_ns = 1'000'000'000;
  image.path = "/data/cam0/data/1000000000.png";
  return image;
}

// A database with the test camera, and a frame's image and features.
struct IngestFixture {
  explicit IngestFixture(const std::string& name)
      : database(ColmapDatabase::Open(testing::MakeScratchFolder(name) / "database.db")),
        camera_id(database.WriteCamera(TestCamera())) {}
  ColmapDatabase database;
  camera_t camera_id;
  ImageFeatures features = TestFeatures();
  SequenceImage image = TestImage();
};

TEST(FrameIngest, StoresNewFeaturesAndSkipsStoredOnes) {
  IngestFixture fixture("frame_ingest_store");
  ColmapDatabase& database = fixture.database;
  const camera_t camera_id = fixture.camera_id;
  const ImageFeatures& features = fixture.features;
  const SequenceImage& image = fixture.image;
  FrameIngest ingest(&database, camera_id, Rigid3d(), 0.0);
  const IngestedFrame first = ingest.Store(image, &features);
  EXPECT_EQ(first.name, DatabaseImageName(image));
  EXPECT_EQ(first.camera_id, camera_id);
  EXPECT_EQ(database.ReadDescriptors(first.image_id), features.descriptors);

  // Stored: read back, not written again (other features would be ignored,
  // and without features the stored ones are taken).
  ImageFeatures other = TestFeatures();
  other.keypoints.pop_back();
  const IngestedFrame again = ingest.Store(image, &other);
  const IngestedFrame resumed = ingest.Store(image, nullptr);
  for (const IngestedFrame* frame : {&again, &resumed}) {
    EXPECT_EQ(frame->image_id, first.image_id);
    ASSERT_EQ(frame->keypoints.size(), features.keypoints.size());
    EXPECT_EQ(frame->keypoints[3].x, features.keypoints[3].x);
  }
  EXPECT_EQ(database.ReadAllImages().size(), 1u);

  // An image row without features (a run killed between the two writes)
  // gets them under its own id.
  SequenceImage second = image;
  second.path = "/data/cam0/data/1100000000.png";
  const image_t row_id = database.WriteImage(DatabaseImageName(second), camera_id);
  EXPECT_EQ(ingest.Store(second, &features).image_id, row_id);
  EXPECT_TRUE(database.ExistsFeatures(row_id));
}

TEST(FrameIngest, MapperAndPairImagesCarryThePoseAndCompensatedKeypoints) {
  IngestFixture fixture("frame_ingest_images");
  const camera_t camera_id = fixture.camera_id;
  const ImageFeatures& features = fixture.features;
  const SequenceImage& image = fixture.image;
  const Rigid3d body_from_cam(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                              Eigen::Vector3d(0.05, -0.02, 0.01));
  const double readout_s = 0.03;
  FrameIngest ingest(&fixture.database, camera_id, body_from_cam, readout_s);

  ArrivingFrame frame;
  frame.image = &image;
  const Rigid3d world_from_body(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())),
      Eigen::Vector3d(1.0, 2.0, 0.5));
  frame.vio_pose = FrameVioPose{world_from_body, VioOdometer{}};
  frame.vio_pose->odometer.segment = 2;
  frame.cam_angular_rate = Eigen::Vector3d(0.4, -0.8, 0.2);
  const IngestedFrame stored = ingest.Store(image, &features);

  const MapperImage mapper = ingest.MapperImageOf(frame, stored);
  EXPECT_EQ(mapper.image_id, stored.image_id);
  EXPECT_EQ(mapper.timestamp_ns, image.timestamp_ns);
  ASSERT_TRUE(mapper.vio_cam_from_world.has_value());
  // A point in the camera frame, moved to the world and back.
  const Eigen::Vector3d point_in_cam(0.2, -0.1, 3.0);
  const Eigen::Vector3d point_in_world = world_from_body * (body_from_cam * point_in_cam);
  EXPECT_LT(((*mapper.vio_cam_from_world) * point_in_world - point_in_cam).norm(), 1e-12);
  EXPECT_EQ(mapper.vio_odometer.segment, 2);
  // The keypoints moved as the rolling-shutter compensation moves them; the
  // stored ones are the raw ones.
  FeatureKeypoints expected = features.keypoints;
  CompensateRollingShutterRotation(TestCamera(), readout_s, frame.cam_angular_rate, &expected);
  ASSERT_EQ(mapper.keypoints.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(mapper.keypoints[k].x, expected[k].x) << k;
    EXPECT_EQ(mapper.keypoints[k].y, expected[k].y) << k;
  }
  EXPECT_NE(mapper.keypoints[4].y, features.keypoints[4].y);
  EXPECT_EQ(stored.keypoints[4].y, features.keypoints[4].y);

  const PairImage with_prior = ingest.PairImageOf(frame, stored, features.descriptors,
                                                  /*use_vio_prior=*/true, /*guided=*/true);
  ASSERT_TRUE(with_prior.world_from_body.has_value());
  EXPECT_EQ(with_prior.odometer.segment, 2);
  EXPECT_EQ(with_prior.points_normalized.size(), features.keypoints.size());
  EXPECT_EQ(with_prior.points_px.size(), features.keypoints.size());
  ASSERT_NE(with_prior.stored_descriptors, nullptr);
  EXPECT_EQ(*with_prior.stored_descriptors, features.descriptors);
  const PairImage without_prior = ingest.PairImageOf(frame, stored, features.descriptors,
                                                     /*use_vio_prior=*/false, /*guided=*/false);
  EXPECT_FALSE(without_prior.world_from_body.has_value());
  EXPECT_TRUE(without_prior.points_px.empty());

  // Without a VIO pose the mapper's frame has none either.
  frame.vio_pose.reset();
  EXPECT_FALSE(ingest.MapperImageOf(frame, stored).vio_cam_from_world.has_value());
  ASSERT_EQ(ingest.Cameras().size(), 1u);
  EXPECT_EQ(ingest.Cameras()[0].camera_id, camera_id);
}

}  // namespace
}  // namespace viosfm

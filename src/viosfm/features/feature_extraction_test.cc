#include "viosfm/features/feature_extraction.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <iostream>

#include "viosfm/io/euroc.h"
#include "viosfm/io/image_io.h"
#include "viosfm/sensor/camera_models.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/scene_model.h"
#include "viosfm/sim/sequence_simulator.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

// Four rendered room frames written as PNG files, as a Sequence. A quarter
// of the EuRoC resolution keeps the test fast.
Sequence RenderedSequence(const fs::path& folder) {
  const Camera camera = MakeCamera(CameraModelId::kOpenCV, 376, 240,
                                   {229.3, 228.6, 183.4, 124.0, -0.28, 0.074, 0.0002, 0.00002});
  const Scene scene = MakeRoomScene(RoomSceneOptions{});
  const RayTable rays(camera);
  Sequence sequence;
  sequence.root = folder;
  sequence.rig.camera = camera;
  sequence.rig.camera.camera_id = 1;
  Eigen::Matrix3d world_from_cam;
  world_from_cam << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Matrix3d rotation =
        Eigen::AngleAxisd(0.6 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix() * world_from_cam;
    const Rigid3d cam_from_world = Rigid3d(rotation, Eigen::Vector3d(0.1 * i, 0.0, 1.4)).Inverse();
    RenderOptions options;
    options.seed = i;
    SequenceImage image;
    image.timestamp_ns = 1000000000LL + 100000000LL * i;
    image.path = folder / (std::to_string(image.timestamp_ns) + ".png");
    WriteGreyPng(image.path, Render(scene, rays, cam_from_world, options));
    sequence.images.push_back(image);
  }
  return sequence;
}

const Sequence& Rendered() {
  static const Sequence sequence = RenderedSequence(testing::MakeScratchFolder("rendered"));
  return sequence;
}

TEST(FeatureExtraction, WritesEveryImageAndResumes) {
  const Sequence& sequence = Rendered();
  const fs::path db_path = testing::MakeScratchFolder("extraction") / "db.db";
  SiftOptions options;
  options.max_num_features = 2000;
  {
    // A first run that is interrupted after two images: here, a run on the
    // first two images only.
    Sequence first_two = sequence;
    first_two.images.resize(2);
    ColmapDatabase database = ColmapDatabase::Open(db_path);
    const FeatureExtractionSummary summary = ExtractFeatures(first_two, options, &database, false);
    EXPECT_EQ(summary.num_extracted, 2u);
    EXPECT_EQ(summary.num_skipped, 0u);
  }
  ColmapDatabase database = ColmapDatabase::Open(db_path);
  const FeatureExtractionSummary summary = ExtractFeatures(sequence, options, &database, false);
  std::cout << summary.ToString() << "\n";
  EXPECT_EQ(summary.num_images, 4u);
  EXPECT_EQ(summary.num_extracted, 2u);
  EXPECT_EQ(summary.num_skipped, 2u);
  EXPECT_GT(summary.MeanFeatures(), 300.0);
  EXPECT_THAT(summary.ToString(), ::testing::HasSubstr("(2 extracted; 2 already stored)"));

  EXPECT_EQ(database.NumCameras(), 1u);
  EXPECT_EQ(database.NumImages(), 4u);
  const Camera stored_camera = database.ReadCamera(1);
  EXPECT_EQ(stored_camera.model_id, sequence.rig.camera.model_id);
  for (size_t i = 0; i < sequence.images.size(); ++i) {
    const std::optional<DatabaseImage> image =
        database.ReadImageWithName(DatabaseImageName(sequence.images[i]));
    ASSERT_TRUE(image.has_value()) << i;
    EXPECT_EQ(image->image_id, i + 1);
    EXPECT_EQ(image->camera_id, 1u);
    EXPECT_TRUE(database.ExistsFeatures(image->image_id));
    // The stored features are exactly those of a direct extraction (checked
    // for one image of each run).
    if (i != 1 && i != 3) continue;
    const ImageFeatures direct = ExtractSift(ReadGreyImage(sequence.images[i].path), options);
    EXPECT_EQ(database.ReadDescriptors(image->image_id), direct.descriptors) << i;
    const FeatureKeypoints keypoints = database.ReadKeypoints(image->image_id);
    ASSERT_EQ(keypoints.size(), direct.keypoints.size());
    EXPECT_EQ(keypoints.back().x, direct.keypoints.back().x);
    EXPECT_EQ(keypoints.back().a21, direct.keypoints.back().a21);
  }

  // Everything stored: nothing to do.
  const FeatureExtractionSummary again = ExtractFeatures(sequence, options, &database, false);
  EXPECT_EQ(again.num_extracted, 0u);
  EXPECT_EQ(again.num_skipped, 4u);
}

// Features given by FeatureImageAccess::take_extracted are written as
// given, without a decode; the other images are extracted as usual.
TEST(FeatureExtraction, TakesFeaturesExtractedBefore) {
  const Sequence& sequence = Rendered();
  ColmapDatabase database =
      ColmapDatabase::Open(testing::MakeScratchFolder("extraction_before") / "db.db");
  SiftOptions options;
  options.max_num_features = 500;
  const ImageFeatures second = ExtractSift(ReadGreyImage(sequence.images[1].path), options);
  FeatureImageAccess access;
  int num_decoded = 0;
  access.on_extracted = [&](image_t, const GreyImage&, const FeatureKeypoints&) {
    ++num_decoded;  // one worker thread: no race
  };
  access.take_extracted = [&](image_t, const SequenceImage& image, ImageFeatures* features) {
    if (image.path != sequence.images[1].path) return false;
    *features = second;
    features->keypoints.resize(7);  // recognisably not what extraction gives
    features->descriptors.conservativeResize(7, Eigen::NoChange);
    return true;
  };
  options.num_threads = 1;
  const FeatureExtractionSummary summary =
      ExtractFeatures(sequence, options, &database, false, access);
  EXPECT_EQ(summary.num_extracted, 4u);
  EXPECT_EQ(summary.num_extracted_before, 1u);
  EXPECT_EQ(num_decoded, 3);
  EXPECT_THAT(summary.ToString(), ::testing::HasSubstr("4 extracted, 1 of them beside the VIO"));
  const image_t id =
      database.ReadImageWithName(sequence.images[1].path.filename().string())->image_id;
  const FeatureKeypoints keypoints = database.ReadKeypoints(id);
  ASSERT_EQ(keypoints.size(), 7u);
  EXPECT_EQ(keypoints[6].x, second.keypoints[6].x);
  EXPECT_EQ(database.ReadDescriptors(id), second.descriptors.topRows(7));
  const image_t other =
      database.ReadImageWithName(sequence.images[2].path.filename().string())->image_id;
  EXPECT_GT(database.ReadKeypoints(other).size(), 100u);
}

TEST(FeatureExtraction, RejectsMismatchedInput) {
  const Sequence& sequence = Rendered();
  const fs::path folder = testing::MakeScratchFolder("extraction_bad");
  SiftOptions options;
  options.max_num_features = 200;

  // An image whose size is not the camera's names the image.
  Sequence wrong_size = sequence;
  wrong_size.rig.camera.width = 320;
  {
    ColmapDatabase database = ColmapDatabase::Open(folder / "size.db");
    try {
      ExtractFeatures(wrong_size, options, &database, false);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr(".png"));
      EXPECT_THAT(e.what(), ::testing::HasSubstr("376 x 240"));
    }
  }
  // Re-running with other intrinsics on a database that holds the images.
  {
    ColmapDatabase database = ColmapDatabase::Open(folder / "camera.db");
    ExtractFeatures(sequence, options, &database, false);
    Sequence other_camera = sequence;
    other_camera.rig.camera.params[0] += 1.0;
    EXPECT_THROW(ExtractFeatures(other_camera, options, &database, false), InputError);
  }
  // Duplicate file names.
  {
    Sequence duplicate = sequence;
    duplicate.images[1].path = folder / "other" / duplicate.images[0].path.filename();
    ColmapDatabase database = ColmapDatabase::Open(folder / "duplicate.db");
    EXPECT_THROW(ExtractFeatures(duplicate, options, &database, false), InputError);
  }
  // A missing image file.
  {
    Sequence missing = sequence;
    missing.images[2].path = folder / "missing.png";
    ColmapDatabase database = ColmapDatabase::Open(folder / "missing.db");
    EXPECT_THROW(ExtractFeatures(missing, options, &database, false), InputError);
    // The images extracted before the failure are kept.
    EXPECT_GE(database.NumKeypoints(), 1u);
  }
}

TEST(FeatureExtraction, RealEurocSequence) {
  VIOSFM_REQUIRE_DATASET(root, "euroc_v101_static_micro");
  Sequence sequence = ReadEurocDataset(root);
  sequence.images.resize(6);
  const fs::path db_path = testing::MakeScratchFolder("extraction_euroc") / "db.db";
  ColmapDatabase database = ColmapDatabase::Open(db_path);
  const FeatureExtractionSummary summary =
      ExtractFeatures(sequence, SiftOptions{}, &database, false);
  std::cout << "EuRoC V1_01, 752x480, 2 threads: " << summary.ToString() << " ("
            << 1e3 * summary.seconds / summary.num_extracted << " ms per image)\n";
  EXPECT_EQ(summary.num_extracted, 6u);
  EXPECT_GE(summary.MeanFeatures(), 500.0);
  EXPECT_EQ(database.ReadImage(1).name, sequence.images[0].path.filename().string());
  // The stored camera is the dataset's (principal point converted back).
  const Camera camera = database.ReadCamera(1);
  EXPECT_NEAR(camera.params[2], sequence.rig.camera.params[2], 1e-12);
}

}  // namespace
}  // namespace viosfm

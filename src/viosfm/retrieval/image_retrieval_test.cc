#include "viosfm/retrieval/image_retrieval.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "viosfm/retrieval/synthetic_test_images.h"
#include "viosfm/sim/renderer.h"
#include "viosfm/sim/scene_model.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/random.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using testing::MakeSyntheticImages;
using testing::SmallOptions;
using testing::SyntheticImages;

using ::testing::Contains;
using ::testing::Not;

// The other images of the same place.
std::vector<image_t> Duplicates(const SyntheticImages& images, size_t index) {
  std::vector<image_t> duplicates;
  for (size_t j = 0; j < images.image_ids.size(); ++j) {
    if (j != index && images.place[j] == images.place[index])
      duplicates.push_back(images.image_ids[j]);
  }
  return duplicates;
}

TEST(RetrieveSimilarImages, RanksNearDuplicatesFirst) {
  const SyntheticImages images = MakeSyntheticImages(5);
  const RetrievalOptions options = SmallOptions();
  const auto loader = [&images](size_t index) { return images.descriptors[index]; };
  const std::vector<std::vector<ImageScore>> scores =
      RetrieveSimilarImageScores(images.image_ids, loader, {}, options);
  ASSERT_EQ(scores.size(), images.image_ids.size());
  int found = 0;
  int expected = 0;
  for (size_t i = 0; i < scores.size(); ++i) {
    ASSERT_EQ(scores[i].size(), 5u) << "image " << i;
    std::vector<image_t> top;
    for (const ImageScore& score : scores[i]) top.push_back(score.image_id);
    EXPECT_THAT(top, Not(Contains(images.image_ids[i])));
    // The duplicates are the top 2.
    for (const image_t duplicate : Duplicates(images, i)) {
      ++expected;
      found += std::find(top.begin(), top.begin() + 2, duplicate) != top.begin() + 2;
    }
    for (size_t r = 1; r < scores[i].size(); ++r)
      EXPECT_GE(scores[i][r - 1].score, scores[i][r].score);
  }
  EXPECT_EQ(found, expected);  // recall@2 (so also @5) = 1.0
}

TEST(RetrieveSimilarImages, LeavesOutTheExclusionSet) {
  const SyntheticImages images = MakeSyntheticImages(5);
  std::vector<std::vector<image_t>> exclude(images.image_ids.size());
  for (size_t i = 0; i < exclude.size(); ++i) exclude[i] = {Duplicates(images, i)[0]};
  const std::vector<std::vector<image_t>> result =
      RetrieveSimilarImages(images.image_ids, images.descriptors, exclude, SmallOptions());
  for (size_t i = 0; i < result.size(); ++i) {
    ASSERT_EQ(result[i].size(), 5u);
    EXPECT_THAT(result[i], Not(Contains(exclude[i][0])));
    EXPECT_THAT(result[i], Not(Contains(images.image_ids[i])));
    EXPECT_EQ(result[i][0], Duplicates(images, i)[1]) << "image " << i;
  }
}

TEST(RetrieveSimilarImages, DeterministicPerSeedAndThreadCount) {
  const SyntheticImages images = MakeSyntheticImages(6);
  const auto loader = [&images](size_t index) { return images.descriptors[index]; };
  RetrievalOptions options = SmallOptions();
  options.num_threads = 1;
  const auto a = RetrieveSimilarImageScores(images.image_ids, loader, {}, options);
  options.num_threads = 3;
  const auto b = RetrieveSimilarImageScores(images.image_ids, loader, {}, options);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].size(), b[i].size());
    for (size_t r = 0; r < a[i].size(); ++r) {
      EXPECT_EQ(a[i][r].image_id, b[i][r].image_id);
      EXPECT_EQ(a[i][r].score, b[i][r].score);
    }
  }
}

TEST(RetrieveSimilarImages, SavedVocabularyGivesIdenticalResults) {
  const SyntheticImages images = MakeSyntheticImages(7);
  const auto loader = [&images](size_t index) { return images.descriptors[index]; };
  RetrievalOptions options = SmallOptions();
  const VocabularyTree tree =
      TrainVocabularyTree(images.image_ids.size(), loader, options.vocabulary);
  const auto path = testing::MakeScratchFolder("retrieval_vocabulary") / "tree.bin";
  tree.Save(path);
  const auto trained = RetrieveSimilarImageScores(images.image_ids, loader, {}, options);
  const auto given = RetrieveSimilarImageScores(images.image_ids, loader, {}, options, &tree);
  options.vocabulary_path = path.string();
  const auto loaded = RetrieveSimilarImageScores(images.image_ids, loader, {}, options);
  ASSERT_EQ(trained.size(), loaded.size());
  for (size_t i = 0; i < trained.size(); ++i) {
    ASSERT_EQ(trained[i].size(), loaded[i].size());
    ASSERT_EQ(given[i].size(), loaded[i].size());
    for (size_t r = 0; r < trained[i].size(); ++r) {
      EXPECT_EQ(trained[i][r].image_id, loaded[i][r].image_id);
      EXPECT_EQ(trained[i][r].score, loaded[i][r].score);
      EXPECT_EQ(given[i][r].image_id, loaded[i][r].image_id);
    }
  }
  options.vocabulary_path = (path.parent_path() / "missing.bin").string();
  EXPECT_THROW(RetrieveSimilarImageScores(images.image_ids, loader, {}, options), InputError);
}

TEST(TemporalNeighborExclusion, WindowAroundEachImage) {
  const std::vector<image_t> ids = {5, 6, 7, 8, 9};
  const auto exclude = TemporalNeighborExclusion(ids, 2);
  EXPECT_EQ(exclude[0], (std::vector<image_t>{6, 7}));
  EXPECT_EQ(exclude[2], (std::vector<image_t>{5, 6, 8, 9}));
  EXPECT_EQ(exclude[4], (std::vector<image_t>{7, 8}));
}

TEST(RetrievalOptions, ValidateNamesTheField) {
  RetrievalOptions options;
  EXPECT_EQ(options.Validate(), "");
  EXPECT_EQ(options.num_neighbors, 30);
  options.num_neighbors = 0;
  EXPECT_NE(options.Validate().find("num_neighbors"), std::string::npos);
  options = {};
  options.vocabulary.depth = 0;
  EXPECT_NE(options.Validate().find("vocabulary.depth"), std::string::npos);
}

// ---------------------------------------------------------- rendered room ----

// cam_from_world of a camera at `position` looking horizontally at `yaw`
// (rad, from the world x axis towards y), z up.
Rigid3d LookAt(const Eigen::Vector3d& position, double yaw) {
  const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << right, down, forward;
  return Rigid3d(world_from_cam, position).Inverse();
}

// RootSIFT of OpenCV SIFT, quantised to uint8 as 512 * sqrt(l1-normalised).
FeatureDescriptors RootSift(const GreyImage& image) {
  const cv::Mat mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data()));
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(800);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  sift->detectAndCompute(mat, cv::noArray(), keypoints, descriptors);
  FeatureDescriptors out(descriptors.rows, 128);
  for (int i = 0; i < descriptors.rows; ++i) {
    const float* row = descriptors.ptr<float>(i);
    double sum = 0.0;
    for (int d = 0; d < 128; ++d) sum += std::abs(row[d]);
    for (int d = 0; d < 128; ++d) {
      const double value = sum > 0 ? 512.0 * std::sqrt(std::abs(row[d]) / sum) : 0.0;
      out(i, d) = static_cast<uint8_t>(std::min(255.0, std::round(value)));
    }
  }
  return out;
}

// Frames of the simulated room: a first tour looking around from one spot
// (8 headings, 45 degrees apart), then a revisit of every heading from
// 0.3 m away and 4 degrees off. Each revisit must retrieve its first visit
// among its top 5.
TEST(RetrieveSimilarImages, RevisitedPlacesInTheRenderedRoom) {
  RoomSceneOptions room;
  room.texels_per_metre = 64.0;  // enough for the half-resolution camera below
  const Scene scene = MakeRoomScene(room);
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kPinhole;
  camera.width = 376;
  camera.height = 240;
  camera.params = {229.0, 229.0, 188.0, 120.0};
  const RayTable rays(camera);
  RenderOptions render;
  render.num_threads = 2;
  constexpr int kHeadings = 8;
  std::vector<image_t> image_ids;
  std::vector<FeatureDescriptors> descriptors;
  for (int visit = 0; visit < 2; ++visit) {
    for (int h = 0; h < kHeadings; ++h) {
      const double yaw = 2.0 * M_PI * h / kHeadings + (visit == 0 ? 0.0 : 4.0 * M_PI / 180.0);
      const Eigen::Vector3d position =
          visit == 0 ? Eigen::Vector3d(0.5, -0.3, 1.4) : Eigen::Vector3d(0.7, -0.1, 1.5);
      render.seed = static_cast<uint64_t>(visit * kHeadings + h);
      descriptors.push_back(RootSift(Render(scene, rays, LookAt(position, yaw), render)));
      image_ids.push_back(static_cast<image_t>(visit * kHeadings + h + 1));
      ASSERT_GT(descriptors.back().rows(), 100) << "frame " << image_ids.back();
    }
  }
  RetrievalOptions options;
  options.num_neighbors = 5;
  options.vocabulary.branching = 8;
  options.vocabulary.depth = 3;
  options.num_threads = 2;
  const auto result = RetrieveSimilarImages(image_ids, descriptors, {}, options);
  int first = 0;
  for (int h = 0; h < kHeadings; ++h) {
    const std::vector<image_t>& top = result[kHeadings + h];
    EXPECT_THAT(top, Contains(image_t(h + 1))) << "heading " << h;
    first += !top.empty() && top[0] == image_t(h + 1);
  }
  RecordProperty("revisits_ranking_first_visit_first", first);
  EXPECT_GE(first, kHeadings - 1);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/pipeline/feature_prefetch.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "viosfm/io/image_io.h"
#include "viosfm/pipeline/stage_colors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 160;
constexpr int kHeight = 120;

// Random 8 x 8 blocks: corners and blobs for SIFT everywhere.
fs::path WriteTexturedImage(const fs::path& folder, int index) {
  std::mt19937 rng(static_cast<uint32_t>(100 + index));
  std::uniform_int_distribution<int> value(0, 255);
  GreyImage image(kWidth, kHeight);
  for (int by = 0; by < kHeight; by += 8) {
    for (int bx = 0; bx < kWidth; bx += 8) {
      const auto v = static_cast<uint8_t>(value(rng));
      for (int y = by; y < by + 8; ++y) {
        for (int x = bx; x < bx + 8; ++x) image.at(x, y) = v;
      }
    }
  }
  const fs::path path = folder / ("frame" + std::to_string(index) + ".png");
  WriteGreyPng(path, image);
  return path;
}

// Finish stops the prefetch at the frame it is on (the features stage takes
// the rest): the tests wait for the frames they expect first.
void WaitUntilExtracted(const FeaturePrefetch& prefetch, size_t n) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (prefetch.num_extracted() < n && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

Camera TestCamera() {
  Camera camera;
  camera.width = kWidth;
  camera.height = kHeight;
  return camera;
}

SiftOptions TestSiftOptions() {
  SiftOptions options;
  options.max_num_features = 200;
  return options;
}

TEST(FeaturePrefetchTest, FollowsTheReaderAndGivesWhatExtractSiftGives) {
  const fs::path folder = testing::MakeScratchFolder("feature_prefetch_follow");
  std::vector<fs::path> paths;
  for (int i = 0; i < 6; ++i) paths.push_back(WriteTexturedImage(folder, i));
  FrameCache cache(size_t{64} << 20);
  // Frames 0, 2, 4 are wanted; the reader (the VIO) reads all six.
  const std::vector<fs::path> wanted = {paths[0], paths[2], paths[4]};
  cache.RetainOnly(wanted);
  FeaturePrefetch prefetch(wanted, TestSiftOptions(), TestCamera(), &cache, size_t{64} << 20);
  for (const fs::path& path : paths) cache.Read(path, /*keep=*/true);
  WaitUntilExtracted(prefetch, 3);
  prefetch.Finish();
  EXPECT_EQ(prefetch.num_extracted(), 3u);
  for (const fs::path& path : wanted) {
    ImageFeatures features;
    std::vector<uint8_t> grey_values;
    ASSERT_TRUE(prefetch.Take(path, &features, &grey_values)) << path;
    const GreyImage pixels = ReadGreyImage(path);
    const ImageFeatures expected = ExtractSift(pixels, TestSiftOptions());
    ASSERT_GT(expected.keypoints.size(), 20u);
    ASSERT_EQ(features.keypoints.size(), expected.keypoints.size());
    for (size_t k = 0; k < expected.keypoints.size(); ++k) {
      EXPECT_EQ(features.keypoints[k].x, expected.keypoints[k].x);
      EXPECT_EQ(features.keypoints[k].y, expected.keypoints[k].y);
    }
    EXPECT_EQ(features.descriptors, expected.descriptors);
    EXPECT_EQ(grey_values, SampleKeypointGreyValues(pixels, expected.keypoints));
    // Taken once: a second Take finds nothing.
    EXPECT_FALSE(prefetch.Take(path, &features, &grey_values));
  }
  ImageFeatures features;
  std::vector<uint8_t> grey_values;
  EXPECT_FALSE(prefetch.Take(paths[1], &features, &grey_values));  // not wanted
  // Each frame decoded once, the wanted ones taken from the cache.
  const FrameCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.decodes, 6u);
  EXPECT_EQ(counts.reuses, 3u);
}

TEST(FeaturePrefetchTest, StopsAtItsBudgetAndLeavesTheRestInTheCache) {
  const fs::path folder = testing::MakeScratchFolder("feature_prefetch_budget");
  std::vector<fs::path> paths;
  for (int i = 0; i < 4; ++i) paths.push_back(WriteTexturedImage(folder, i));
  FrameCache cache(size_t{64} << 20);
  // A budget of one byte: the first frame's features exceed it.
  FeaturePrefetch prefetch(paths, TestSiftOptions(), TestCamera(), &cache, 1);
  for (const fs::path& path : paths) cache.Read(path, /*keep=*/true);
  WaitUntilExtracted(prefetch, 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // time to go on, if it did
  prefetch.Finish();
  EXPECT_EQ(prefetch.num_extracted(), 1u);
  EXPECT_GT(prefetch.peak_bytes(), 128u * 20u);
  // The other three wait in the cache for the features stage.
  for (size_t i = 1; i < paths.size(); ++i) cache.Take(paths[i]);
  EXPECT_EQ(cache.counts().decodes, 4u);
}

TEST(FeaturePrefetchTest, FramesTheReaderNeverReadsAreLeftToTheFeaturesStage) {
  const fs::path folder = testing::MakeScratchFolder("feature_prefetch_unread");
  std::vector<fs::path> paths;
  for (int i = 0; i < 3; ++i) paths.push_back(WriteTexturedImage(folder, i));
  FrameCache cache(size_t{64} << 20);
  FeaturePrefetch prefetch(paths, TestSiftOptions(), TestCamera(), &cache, size_t{64} << 20);
  cache.Read(paths[0], /*keep=*/true);  // the reader stops after one frame
  WaitUntilExtracted(prefetch, 1);
  prefetch.Finish();  // returns: does not wait for the others
  EXPECT_EQ(prefetch.num_extracted(), 1u);
  EXPECT_EQ(cache.counts().decodes, 1u);
}

TEST(FeaturePrefetchTest, AFrameOfTheWrongSizeIsLeftToTheFeaturesStage) {
  const fs::path folder = testing::MakeScratchFolder("feature_prefetch_size");
  const fs::path good = WriteTexturedImage(folder, 0);
  const fs::path small = folder / "small.png";
  WriteGreyPng(small, GreyImage(kWidth / 2, kHeight / 2, 7));
  const fs::path after = WriteTexturedImage(folder, 1);
  FrameCache cache(size_t{64} << 20);
  FeaturePrefetch prefetch({good, small, after}, TestSiftOptions(), TestCamera(), &cache,
                           size_t{64} << 20);
  for (const fs::path& path : {good, small, after}) cache.Read(path, /*keep=*/true);
  WaitUntilExtracted(prefetch, 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // time to go on, if it did
  prefetch.Finish();
  // It stops at the wrong size: the features stage reads it again and
  // names the file and the size (feature_extraction.h).
  EXPECT_EQ(prefetch.num_extracted(), 1u);
  ImageFeatures features;
  std::vector<uint8_t> grey_values;
  EXPECT_TRUE(prefetch.Take(good, &features, &grey_values));
  EXPECT_FALSE(prefetch.Take(small, &features, &grey_values));
  EXPECT_FALSE(prefetch.Take(after, &features, &grey_values));
}

}  // namespace
}  // namespace viosfm

#include "viosfm/pipeline/texture_probe.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "viosfm/io/image_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr int kWidth = 240;
constexpr int kHeight = 180;
constexpr int kCap = 150;

// Blocks of 6 px of random grey: corners and blobs everywhere.
GreyImage TexturedImage(uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  GreyImage image(kWidth, kHeight);
  for (int by = 0; by < kHeight; by += 6) {
    for (int bx = 0; bx < kWidth; bx += 6) {
      const auto value = static_cast<uint8_t>(grey(random));
      for (int y = by; y < std::min(by + 6, kHeight); ++y) {
        for (int x = bx; x < std::min(bx + 6, kWidth); ++x) image.at(x, y) = value;
      }
    }
  }
  return image;
}

// A sequence of `num_frames` images, those in `bare` a uniform grey (no
// keypoint at all), the others textured.
Sequence MakeSequence(const std::string& name, int num_frames, const std::vector<int>& bare) {
  const std::filesystem::path folder = testing::MakeScratchFolder(name);
  Sequence sequence;
  sequence.root = folder;
  for (int k = 0; k < num_frames; ++k) {
    const bool is_bare = std::find(bare.begin(), bare.end(), k) != bare.end();
    const std::filesystem::path path = folder / (std::to_string(k) + ".png");
    WriteGreyPng(path, is_bare ? GreyImage(kWidth, kHeight, 128) : TexturedImage(k + 1));
    sequence.images.push_back({static_cast<timestamp_ns_t>(k) * 100'000'000, path});
  }
  return sequence;
}

std::vector<size_t> AllFrames(const Sequence& sequence) {
  std::vector<size_t> frames(sequence.images.size());
  for (size_t k = 0; k < frames.size(); ++k) frames[k] = k;
  return frames;
}

TextureProbeOptions ProbeOptions() {
  TextureProbeOptions options;
  options.enable = true;
  options.num_frames = 10;
  options.max_num_features = kCap;
  return options;
}

TEST(ProbeTexture, EveryFrameRichInKeypointsIsTextured) {
  const Sequence sequence = MakeSequence("probe_textured", 10, {});
  FrameCache cache(1 << 26);
  const TextureProbeResult result =
      ProbeTexture(sequence, AllFrames(sequence), SiftOptions(), ProbeOptions(), &cache);
  ASSERT_TRUE(result.probed);
  EXPECT_EQ(result.frames.size(), 10u);
  for (const int count : result.num_keypoints) EXPECT_EQ(count, kCap);
  EXPECT_EQ(result.deciding_count, kCap);
  EXPECT_TRUE(result.textured);
  EXPECT_THAT(result.ToString(ProbeOptions()), HasSubstr("textured: 150 of 150 keypoints"));
  // The probed frames are held for the stages after: taking them decodes nothing.
  EXPECT_EQ(cache.counts().decodes, 10u);
  for (const SequenceImage& image : sequence.images) cache.Take(image.path);
  EXPECT_EQ(cache.counts().decodes, 10u);
  EXPECT_EQ(cache.counts().reuses, 10u);
}

TEST(ProbeTexture, AFewBareFramesKeepTheRateUnlessThePercentileIgnoresThem) {
  // Three of ten frames are a bare wall: no keypoint.
  const Sequence sequence = MakeSequence("probe_bare", 10, {2, 5, 8});
  FrameCache cache(1 << 26);
  TextureProbeOptions options = ProbeOptions();
  const TextureProbeResult result =
      ProbeTexture(sequence, AllFrames(sequence), SiftOptions(), options, &cache);
  ASSERT_TRUE(result.probed);
  // The 10th percentile of ten frames is the second fewest: once two frames
  // fall short (frames 2 and 5, probed two at a time), it can only be
  // short, and the probe stops after frames 4 and 5.
  EXPECT_EQ(result.num_planned, 10u);
  ASSERT_EQ(result.frames.size(), 6u);
  EXPECT_EQ(result.num_keypoints[2], 0);
  EXPECT_EQ(result.num_keypoints[5], 0);
  EXPECT_EQ(result.num_keypoints[0], kCap);
  EXPECT_EQ(result.deciding_count, 0);
  EXPECT_FALSE(result.textured);
  EXPECT_THAT(result.ToString(options),
              HasSubstr("not textured: 2 of the first 6 of 10 frames probed hold fewer than 135"));

  // The median frame is textured: a percentile of 0.5 calls it textured,
  // having probed every frame (the short ones never outnumber the rank).
  options.percentile = 0.5;
  const TextureProbeResult median =
      ProbeTexture(sequence, AllFrames(sequence), SiftOptions(), options, &cache);
  ASSERT_EQ(median.frames.size(), 10u);
  EXPECT_EQ(median.num_keypoints[8], 0);
  EXPECT_EQ(median.deciding_count, kCap);
  EXPECT_TRUE(median.textured);
}

TEST(ProbeTexture, ProbedFramesAreSpreadEvenlyOverTheCandidates) {
  const Sequence sequence = MakeSequence("probe_spread", 20, {});
  std::vector<size_t> candidates;
  for (size_t k = 1; k < 20; k += 2) candidates.push_back(k);  // 10 frames: 1, 3, ..., 19
  TextureProbeOptions options = ProbeOptions();
  options.num_frames = 4;
  FrameCache cache(1 << 26);
  const TextureProbeResult result =
      ProbeTexture(sequence, candidates, SiftOptions(), options, &cache);
  // The middle of each quarter of the candidates.
  EXPECT_THAT(result.frames, ElementsAre(3u, 7u, 13u, 17u));
}

TEST(ProbeTexture, DisabledOrInvalid) {
  const Sequence sequence = MakeSequence("probe_disabled", 2, {});
  FrameCache cache(1 << 26);
  TextureProbeOptions options = ProbeOptions();
  options.enable = false;
  const TextureProbeResult result =
      ProbeTexture(sequence, AllFrames(sequence), SiftOptions(), options, &cache);
  EXPECT_FALSE(result.probed);
  EXPECT_EQ(cache.counts().decodes, 0u);
  EXPECT_EQ(result.ToString(options), "not probed");

  options.enable = true;
  options.min_fraction = 0.0;
  EXPECT_THAT(testing::InputErrorMessage([&] {
                ProbeTexture(sequence, AllFrames(sequence), SiftOptions(), options, &cache);
              }),
              HasSubstr("min_fraction must be in (0, 1]"));
  options = ProbeOptions();
  options.num_frames = 0;
  EXPECT_THAT(options.Validate(), HasSubstr("num_frames"));
  options = ProbeOptions();
  options.percentile = 1.5;
  EXPECT_THAT(options.Validate(), HasSubstr("percentile"));
  options = ProbeOptions();
  options.target_rate_hz = 0.0;
  EXPECT_THAT(options.Validate(), HasSubstr("target_rate_hz"));
}

// The budget of features a second: 1000 a frame at 10 Hz on images of at
// most 800 px, 2500 at 4 Hz; frames slower than budget / cap, photos without
// stamps and a budget of 0 are not limited; the rate is the target's or the
// camera's where that is slower.
TEST(FeatureBudget, SpreadsTheFeaturesOverTheFramesOfASecond) {
  FeatureBudgetOptions budget;
  budget.features_per_second = 10000;
  SiftOptions sift;
  sift.max_num_features = 8192;
  sift.max_image_size = 0;
  SiftOptions at_10_hz = sift;
  EXPECT_NE(ApplyFeatureBudget(budget, 10.0, &at_10_hz), "");
  EXPECT_EQ(at_10_hz.max_num_features, 1000);
  EXPECT_EQ(at_10_hz.max_image_size, 800);
  SiftOptions at_4_hz = sift;
  ApplyFeatureBudget(budget, 4.0, &at_4_hz);
  EXPECT_EQ(at_4_hz.max_num_features, 2500);
  SiftOptions smaller_images = sift;
  smaller_images.max_image_size = 640;
  ApplyFeatureBudget(budget, 10.0, &smaller_images);
  EXPECT_EQ(smaller_images.max_image_size, 640);
  for (const double slow_hz : {1.2, 0.5, 0.0}) {
    SiftOptions slow = sift;
    EXPECT_EQ(ApplyFeatureBudget(budget, slow_hz, &slow), "") << slow_hz;
    EXPECT_EQ(slow.max_num_features, 8192);
    EXPECT_EQ(slow.max_image_size, 0);
  }
  FeatureBudgetOptions off;
  SiftOptions unlimited = sift;
  EXPECT_EQ(ApplyFeatureBudget(off, 10.0, &unlimited), "");
  EXPECT_EQ(unlimited.max_num_features, 8192);

  Sequence sequence;
  for (int k = 0; k <= 40; ++k) {  // 20 Hz over 2 s
    SequenceImage image;
    image.timestamp_ns = k * 50'000'000;
    sequence.images.push_back(image);
  }
  EXPECT_DOUBLE_EQ(ReconstructionRateHz(sequence, 10.0), 10.0);
  EXPECT_DOUBLE_EQ(ReconstructionRateHz(sequence, 0.0), 20.0);
  EXPECT_DOUBLE_EQ(ReconstructionRateHz(sequence, 50.0), 20.0);
  sequence.unordered = true;
  EXPECT_EQ(ReconstructionRateHz(sequence, 10.0), 0.0);
  Sequence just_begun;
  just_begun.images.resize(1);
  EXPECT_DOUBLE_EQ(ReconstructionRateHz(just_begun, 10.0), 10.0);
}

}  // namespace
}  // namespace viosfm

#include "viosfm/sfm/vio_gaps.h"

#include <gtest/gtest.h>

#include <vector>

namespace viosfm {
namespace {

// Ten frames of one VIO segment with gaps before frames 3, 6 and 8 (their
// VioOdometer::gap counts 0 0 0 1 1 1 2 2 3 3), and pairs between them.
BatchedMapperInput MakeInput() {
  BatchedMapperInput input;
  const std::vector<int> gaps = {0, 0, 0, 1, 1, 1, 2, 2, 3, 3};
  for (size_t i = 0; i < gaps.size(); ++i) {
    MapperImage image;
    image.image_id = static_cast<image_t>(i + 1);
    image.name = "frame" + std::to_string(i + 1);
    image.timestamp_ns = static_cast<timestamp_ns_t>(i) * 1'000'000'000;
    image.vio_cam_from_world = Rigid3d();
    image.vio_odometer.gap = gaps[i];
    input.images.push_back(image);
  }
  return input;
}

ImagePairMatches Pair(image_t a, image_t b, bool contradicted) {
  ImagePairMatches pair;
  pair.image_id1 = a;
  pair.image_id2 = b;
  pair.matches.resize(50);
  pair.vio_contradicted = contradicted;
  return pair;
}

TEST(VioGapsTest, ConfirmedGapsKeepOneSegmentAndAJumpSplitsIt) {
  BatchedMapperInput input = MakeInput();
  input.verified_pairs = {
      Pair(1, 2, false),  Pair(2, 3, false),  // within the first stretch
      Pair(3, 4, false),  Pair(2, 4, false),  // across gap 1: confirmed
      Pair(3, 4, true),                       // a look-alike against the VIO: dropped
      Pair(6, 7, true),   Pair(5, 7, true),   // across gap 2: the VIO jumped
      Pair(8, 9, false),                      // across gap 3: confirmed
  };
  const VioGapSummary summary = DecideVioGaps(&input);
  EXPECT_EQ(summary.num_gaps, 3);
  EXPECT_EQ(summary.num_confirmed, 2);
  EXPECT_EQ(summary.num_jumps, 1);
  EXPECT_EQ(summary.num_unseen, 0);
  EXPECT_EQ(summary.num_pairs_dropped, 1);
  EXPECT_EQ(summary.num_segments, 2);
  std::vector<int> segments;
  for (const MapperImage& image : input.images) segments.push_back(image.vio_odometer.segment);
  EXPECT_EQ(segments, (std::vector<int>{0, 0, 0, 0, 0, 0, 1, 1, 1, 1}));
  // The pairs across the jump stay: they join its two sides.
  EXPECT_EQ(input.verified_pairs.size(), 7u);
}

TEST(VioGapsTest, AGapWithoutPairsIsABreak) {
  BatchedMapperInput input = MakeInput();
  input.verified_pairs = {Pair(1, 2, false), Pair(3, 4, false), Pair(8, 9, false)};
  const VioGapSummary summary = DecideVioGaps(&input);
  EXPECT_EQ(summary.num_confirmed, 2);
  EXPECT_EQ(summary.num_unseen, 1);
  EXPECT_EQ(summary.num_segments, 2);
  EXPECT_EQ(input.images[5].vio_odometer.segment, 0);
  EXPECT_EQ(input.images[6].vio_odometer.segment, 1);
}

TEST(VioGapsTest, APairAcrossSeveralGapsConfirmsEach) {
  BatchedMapperInput input = MakeInput();
  // Frame 1 with frame 10 crosses all three gaps.
  input.verified_pairs = {Pair(1, 10, false)};
  const VioGapSummary summary = DecideVioGaps(&input);
  EXPECT_EQ(summary.num_confirmed, 3);
  EXPECT_EQ(summary.num_segments, 1);
}

TEST(VioGapsTest, FramesWithoutVioPosesAndNoGapsAreLeftAlone) {
  BatchedMapperInput input = MakeInput();
  for (MapperImage& image : input.images) image.vio_odometer.gap = 0;
  input.images[4].vio_cam_from_world.reset();
  input.verified_pairs = {Pair(1, 2, true)};
  const VioGapSummary summary = DecideVioGaps(&input);
  EXPECT_EQ(summary.num_gaps, 0);
  EXPECT_EQ(summary.num_segments, 1);
  EXPECT_EQ(input.verified_pairs.size(), 1u);
}

}  // namespace
}  // namespace viosfm

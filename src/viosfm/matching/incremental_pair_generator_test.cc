#include "viosfm/matching/incremental_pair_generator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "viosfm/util/random.h"

namespace viosfm {
namespace {

// Frames with irregular stamps and random retrieval rankings over all frames.
struct Frames {
  std::vector<PairGeneratorImage> images;
  std::vector<std::vector<image_t>> retrieval;
};

Frames MakeFrames(size_t count, uint64_t seed) {
  Random random(seed);
  Frames frames;
  timestamp_ns_t stamp = 1'000'000'000;
  for (size_t k = 0; k < count; ++k) {
    stamp += static_cast<timestamp_ns_t>(random.UniformInt(1, 40)) * 10'000'000;
    frames.images.push_back({static_cast<image_t>(100 + k), stamp});
  }
  for (size_t k = 0; k < count; ++k) {
    std::vector<image_t> ranked;
    for (const PairGeneratorImage& image : frames.images) ranked.push_back(image.image_id);
    std::shuffle(ranked.begin(), ranked.end(), random.engine());
    frames.retrieval.push_back(ranked);
  }
  return frames;
}

// The pairs of every frame with its N1 nearest in time and with its first N2
// retrieved frames beyond those, straight from the definition.
std::vector<ImagePair> ExpectedPairs(const Frames& frames, int n1, int n2) {
  std::vector<ImagePair> pairs;
  const size_t count = frames.images.size();
  for (size_t k = 0; k < count; ++k) {
    std::vector<std::pair<timestamp_ns_t, size_t>> by_gap;
    for (size_t i = 0; i < count; ++i) {
      if (i == k) continue;
      const timestamp_ns_t gap =
          std::abs(frames.images[i].timestamp_ns - frames.images[k].timestamp_ns);
      by_gap.emplace_back(gap, i);  // on equal gaps the earlier first
    }
    std::sort(by_gap.begin(), by_gap.end());
    std::vector<image_t> taken = {frames.images[k].image_id};
    for (int n = 0; n < n1 && n < static_cast<int>(by_gap.size()); ++n) {
      taken.push_back(frames.images[by_gap[n].second].image_id);
      pairs.push_back(ImagePair::Ordered(frames.images[k].image_id, taken.back()));
    }
    int added = 0;
    for (const image_t candidate :
         frames.retrieval.empty() ? std::vector<image_t>{} : frames.retrieval[k]) {
      if (added >= n2) break;
      if (std::find(taken.begin(), taken.end(), candidate) != taken.end()) continue;
      taken.push_back(candidate);
      pairs.push_back(ImagePair::Ordered(frames.images[k].image_id, candidate));
      ++added;
    }
  }
  return SortAndDeduplicatePairs(pairs);
}

std::vector<ImagePair> AllPairs(IncrementalPairGenerator* generator) {
  std::vector<ImagePair> pairs;
  size_t frame = 0;
  std::vector<ProposedPair> proposed;
  while (generator->Next(&frame, &proposed)) {
    for (const ProposedPair& pair : proposed) {
      EXPECT_LT(pair.earlier_frame, frame);
      pairs.push_back(ImagePair::Ordered(generator->image(pair.earlier_frame).image_id,
                                         generator->image(frame).image_id));
    }
  }
  return SortAndDeduplicatePairs(pairs);
}

TEST(IncrementalPairGenerator, AWholeRecordingGivesTheTemporalRetrievalPairs) {
  const Frames frames = MakeFrames(60, 3);
  PairGeneratorOptions options;
  options.num_temporal_neighbors = 6;
  options.num_retrieval_neighbors = 4;
  IncrementalPairGenerator generator(options);
  for (const PairGeneratorImage& image : frames.images) generator.AddFrame(image);
  for (size_t k = 0; k < frames.images.size(); ++k) generator.SetRetrieved(k, frames.retrieval[k]);
  generator.FinishFrames();
  const std::vector<ImagePair> pairs = AllPairs(&generator);
  EXPECT_TRUE(generator.HasFinished());
  EXPECT_EQ(pairs, ExpectedPairs(frames, 6, 4));
  EXPECT_EQ(TemporalRetrievalPairs(frames.images, frames.retrieval, 6, 4), pairs);
}

TEST(IncrementalPairGenerator, AFrameIsDecidedOnceItsNeighboursAreFixed) {
  const Frames frames = MakeFrames(30, 5);
  PairGeneratorOptions options;
  options.num_temporal_neighbors = 4;
  options.num_retrieval_neighbors = 0;
  IncrementalPairGenerator generator(options);
  size_t frame = 0;
  std::vector<ProposedPair> pairs;
  std::vector<ImagePair> streamed;
  for (size_t k = 0; k < frames.images.size(); ++k) {
    generator.AddFrame(frames.images[k]);
    while (generator.Next(&frame, &pairs)) {
      // Decided only once the 4 frames after it are in.
      EXPECT_GE(k, frame + 4);
      for (const ProposedPair& pair : pairs) {
        streamed.push_back(ImagePair::Ordered(frames.images[pair.earlier_frame].image_id,
                                              frames.images[frame].image_id));
      }
    }
  }
  EXPECT_FALSE(generator.HasFinished());
  generator.FinishFrames();
  while (generator.Next(&frame, &pairs)) {
    for (const ProposedPair& pair : pairs) {
      streamed.push_back(ImagePair::Ordered(frames.images[pair.earlier_frame].image_id,
                                            frames.images[frame].image_id));
    }
  }
  EXPECT_TRUE(generator.HasFinished());
  Frames without_retrieval = frames;
  without_retrieval.retrieval.clear();
  EXPECT_EQ(SortAndDeduplicatePairs(streamed), ExpectedPairs(without_retrieval, 4, 0));
}

TEST(IncrementalPairGenerator, RetrievalAmongEarlierFramesWaitsForEachFrame) {
  const Frames frames = MakeFrames(20, 7);
  PairGeneratorOptions options;
  options.num_temporal_neighbors = 2;
  options.num_retrieval_neighbors = 3;
  IncrementalPairGenerator generator(options);
  for (const PairGeneratorImage& image : frames.images) generator.AddFrame(image);
  generator.FinishFrames();
  size_t frame = 0;
  std::vector<ProposedPair> pairs;
  EXPECT_FALSE(generator.Next(&frame, &pairs));  // frame 0's retrieval unknown
  generator.SetRetrieved(0, {});
  ASSERT_TRUE(generator.Next(&frame, &pairs));
  EXPECT_EQ(frame, 0u);
  EXPECT_TRUE(pairs.empty());
  // Frame 1 retrieves frame 0 (also its temporal neighbour) and nothing else.
  generator.SetRetrieved(1, {frames.images[0].image_id});
  ASSERT_TRUE(generator.Next(&frame, &pairs));
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(std::string(pairs[0].source), "temporal");
}

TEST(IncrementalPairGenerator, SequentialAndExhaustive) {
  const Frames frames = MakeFrames(12, 9);
  PairGeneratorOptions sequential;
  sequential.mode = PairMode::kSequential;
  sequential.num_temporal_neighbors = 3;
  IncrementalPairGenerator by_sequence(sequential);
  PairGeneratorOptions exhaustive;
  exhaustive.mode = PairMode::kExhaustive;
  IncrementalPairGenerator by_all(exhaustive);
  for (const PairGeneratorImage& image : frames.images) {
    by_sequence.AddFrame(image);
    by_all.AddFrame(image);
  }
  by_sequence.FinishFrames();
  by_all.FinishFrames();
  EXPECT_EQ(AllPairs(&by_sequence), SequentialPairs(frames.images, 3));
  EXPECT_EQ(AllPairs(&by_all), ExhaustivePairs(frames.images));
}

}  // namespace
}  // namespace viosfm

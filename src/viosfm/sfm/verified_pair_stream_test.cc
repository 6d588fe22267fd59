#include "viosfm/sfm/verified_pair_stream.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <random>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

using ::testing::HasSubstr;

// Frames 1..n at 0.1 s.
VerifiedPairStream MakeStream(size_t n) {
  std::vector<image_t> ids;
  std::vector<timestamp_ns_t> stamps;
  for (size_t i = 0; i < n; ++i) {
    ids.push_back(static_cast<image_t>(i + 1));
    stamps.push_back(static_cast<timestamp_ns_t>(i) * 100'000'000);
  }
  return VerifiedPairStream(ids, stamps);
}

timestamp_ns_t StampOf(image_t id) {
  return static_cast<timestamp_ns_t>(id - 1) * 100'000'000;
}

ImagePairMatches Pair(image_t a, image_t b, size_t num_matches = 1) {
  ImagePairMatches pair{a, b, {}};
  pair.matches.resize(num_matches);
  return pair;
}

std::set<std::pair<image_t, image_t>> Ids(const std::vector<ImagePairMatches>& pairs) {
  std::set<std::pair<image_t, image_t>> ids;
  for (const ImagePairMatches& pair : pairs) ids.emplace(pair.image_id1, pair.image_id2);
  return ids;
}

TEST(VerifiedPairStream, TakesThePairsOfTheFramesPassed) {
  VerifiedPairStream stream = MakeStream(6);
  // Pairs (5, 2) and (3, 4): earlier frames 2 and 3 (indices 1 and 2).
  stream.Add({Pair(5, 2), Pair(3, 4)}, StampOf(3));
  // Frames [0, 2) are passed: the frontier (frame 3's stamp) is past frame 2's.
  EXPECT_EQ(Ids(stream.TakeUntil(2)), (std::set<std::pair<image_t, image_t>>{{5, 2}}));
  // Nothing new for frame index 1 again.
  EXPECT_TRUE(stream.TakeUntil(2).empty());
  stream.Add({Pair(3, 6), Pair(6, 5)}, StampOf(6));
  EXPECT_EQ(Ids(stream.TakeUntil(5)),
            (std::set<std::pair<image_t, image_t>>{{3, 4}, {3, 6}, {6, 5}}));
  stream.Close();
  EXPECT_TRUE(stream.TakeUntil(6).empty());
  // A pair behind the frontier would be lost: the producer's bug.
  EXPECT_THAT([&] { stream.Add({Pair(1, 2)}, StampOf(6)); },
              ::testing::ThrowsMessage<InternalError>(HasSubstr("behind the frontier")));
}

TEST(VerifiedPairStream, WaitsUntilTheFrontierPassesTheFrames) {
  VerifiedPairStream stream = MakeStream(4);
  // Set before the second Add, whose lock orders it before the consumer's
  // wake-up: the consumer sees it unless it returned on the first Add alone.
  std::atomic<bool> second_add_started{false};
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    stream.Add({Pair(1, 2, 7)}, StampOf(2));  // frame 2 not passed yet
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    second_add_started = true;
    stream.Add({Pair(2, 4, 9)}, StampOf(3));
  });
  const std::vector<ImagePairMatches> taken = stream.TakeUntil(2);
  EXPECT_TRUE(second_add_started);  // frame index 1 (id 2) is passed only by the second Add
  producer.join();
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].matches.size(), 7u);
  EXPECT_EQ(taken[1].matches.size(), 9u);
}

// Pairs in a random order of their earlier frames' handfuls, taken in
// batches by a consumer on another thread: every pair is taken once, with
// the batch of its earlier frame, whatever the timing.
TEST(VerifiedPairStream, EveryPairTakenOnceWithItsEarlierFramesBatch) {
  constexpr size_t kFrames = 60;
  std::mt19937 random(3);
  std::vector<ImagePairMatches> pairs;
  for (image_t a = 1; a <= kFrames; ++a) {
    for (image_t b = a + 1; b <= std::min<image_t>(kFrames, a + 5); ++b) {
      pairs.push_back(random() % 2 ? Pair(a, b) : Pair(b, a));
    }
    pairs.push_back(Pair(a, static_cast<image_t>(1 + random() % kFrames)));
    if (pairs.back().image_id1 == pairs.back().image_id2) pairs.pop_back();
  }
  const auto first = [](const ImagePairMatches& pair) {
    return std::min(pair.image_id1, pair.image_id2);
  };
  std::stable_sort(pairs.begin(), pairs.end(),
                   [&](const auto& x, const auto& y) { return first(x) < first(y); });
  VerifiedPairStream stream = MakeStream(kFrames);
  std::thread producer([&] {
    size_t begin = 0;
    while (begin < pairs.size()) {
      const size_t end = std::min(pairs.size(), begin + 1 + random() % 13);
      std::vector<ImagePairMatches> handful(pairs.begin() + static_cast<ptrdiff_t>(begin),
                                            pairs.begin() + static_cast<ptrdiff_t>(end));
      std::shuffle(handful.begin(), handful.end(), random);
      stream.Add(std::move(handful), end < pairs.size() ? StampOf(first(pairs[end]))
                                                        : std::numeric_limits<int64_t>::max());
      begin = end;
    }
  });
  size_t num_taken = 0;
  size_t batch_begin = 0;
  for (size_t end = 7; end < kFrames + 7; end += 7) {
    const size_t batch_end = std::min(end, kFrames);
    const std::vector<ImagePairMatches> taken = stream.TakeUntil(batch_end);
    std::multiset<std::pair<image_t, image_t>> expected;
    for (const ImagePairMatches& pair : pairs) {
      if (first(pair) > batch_begin && first(pair) <= batch_end) {
        expected.emplace(pair.image_id1, pair.image_id2);
      }
    }
    std::multiset<std::pair<image_t, image_t>> got;
    for (const ImagePairMatches& pair : taken) got.emplace(pair.image_id1, pair.image_id2);
    EXPECT_EQ(got, expected) << "frames up to " << batch_end;
    // By earlier frame.
    EXPECT_TRUE(std::is_sorted(taken.begin(), taken.end(),
                               [&](const auto& x, const auto& y) { return first(x) < first(y); }));
    num_taken += taken.size();
    batch_begin = batch_end;
  }
  producer.join();
  EXPECT_EQ(num_taken, pairs.size());
}

TEST(VerifiedPairStream, TheProducersFailureReachesTheConsumer) {
  VerifiedPairStream stream = MakeStream(3);
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    stream.Fail("frame 2: no descriptors");
  });
  EXPECT_THAT([&] { stream.TakeUntil(3); },
              ::testing::ThrowsMessage<std::runtime_error>(HasSubstr("frame 2: no descriptors")));
  producer.join();
}

TEST(VerifiedPairStream, APairOfAnUnknownImageIsRefused) {
  VerifiedPairStream stream = MakeStream(3);
  EXPECT_THAT([&] { stream.Add({Pair(1, 9)}, StampOf(1)); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("unknown image id 9")));
}

}  // namespace
}  // namespace viosfm

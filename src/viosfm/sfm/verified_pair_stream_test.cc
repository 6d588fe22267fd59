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
  // Pairs (1, 2) and (3, 4): later frames 2 and 4 (indices 1 and 3).
  stream.Add({Pair(2, 1), Pair(3, 4)}, StampOf(3));
  // Frames [0, 2) are passed: the frontier (frame 3's stamp) is past frame 2's.
  VerifiedPairStream::Taken taken = stream.Take(2);
  EXPECT_EQ(Ids(taken.pairs), (std::set<std::pair<image_t, image_t>>{{2, 1}}));
  EXPECT_EQ(taken.end, 2u);
  EXPECT_FALSE(taken.last);
  EXPECT_TRUE(taken.frames.empty());  // known up front
  // Nothing new for frame index 1 again.
  EXPECT_TRUE(stream.Take(2).pairs.empty());
  stream.Add({Pair(3, 6), Pair(5, 6), Pair(5, 2)}, StampOf(6));
  EXPECT_EQ(Ids(stream.Take(5).pairs), (std::set<std::pair<image_t, image_t>>{{3, 4}, {5, 2}}));
  stream.Close();
  taken = stream.Take(6);
  EXPECT_EQ(Ids(taken.pairs), (std::set<std::pair<image_t, image_t>>{{3, 6}, {5, 6}}));
  EXPECT_TRUE(taken.last);
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
    stream.Add({Pair(2, 1, 9)}, StampOf(3));
  });
  const std::vector<ImagePairMatches> taken = stream.Take(2).pairs;
  EXPECT_TRUE(second_add_started);  // frame index 1 (id 2) is passed only by the second Add
  producer.join();
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].matches.size(), 7u);
  EXPECT_EQ(taken[1].matches.size(), 9u);
}

// Pairs in a random order of their later frames' handfuls (each frame's
// with any frame before it, as a verification that pairs every new frame
// with its temporal neighbours and with retrieved older frames), taken in
// batches by a consumer on another thread: every pair is taken once, with
// the batch of its later frame, whatever the timing.
TEST(VerifiedPairStream, EveryPairTakenOnceWithItsLaterFramesBatch) {
  constexpr size_t kFrames = 60;
  std::mt19937 random(3);
  std::vector<ImagePairMatches> pairs;
  for (image_t b = 2; b <= kFrames; ++b) {
    for (image_t a = b > 5 ? b - 5 : 1; a < b; ++a) {
      pairs.push_back(random() % 2 ? Pair(a, b) : Pair(b, a));
    }
    const image_t older = static_cast<image_t>(1 + random() % (b - 1));
    pairs.push_back(Pair(b, older));
  }
  const auto later = [](const ImagePairMatches& pair) {
    return std::max(pair.image_id1, pair.image_id2);
  };
  VerifiedPairStream stream = MakeStream(kFrames);
  std::thread producer([&] {
    size_t begin = 0;
    while (begin < pairs.size()) {
      const size_t end = std::min(pairs.size(), begin + 1 + random() % 13);
      std::vector<ImagePairMatches> handful(pairs.begin() + static_cast<ptrdiff_t>(begin),
                                            pairs.begin() + static_cast<ptrdiff_t>(end));
      std::shuffle(handful.begin(), handful.end(), random);
      stream.Add(std::move(handful), end < pairs.size() ? StampOf(later(pairs[end]))
                                                        : std::numeric_limits<int64_t>::max());
      begin = end;
    }
  });
  size_t num_taken = 0;
  size_t batch_begin = 0;
  for (size_t end = 7; end < kFrames + 7; end += 7) {
    const size_t batch_end = std::min(end, kFrames);
    const VerifiedPairStream::Taken taken = stream.Take(batch_end);
    EXPECT_EQ(taken.end, batch_end);
    EXPECT_EQ(taken.last, batch_end == kFrames);
    std::multiset<std::pair<image_t, image_t>> expected;
    for (const ImagePairMatches& pair : pairs) {
      if (later(pair) > batch_begin && later(pair) <= batch_end) {
        expected.emplace(pair.image_id1, pair.image_id2);
      }
    }
    std::multiset<std::pair<image_t, image_t>> got;
    for (const ImagePairMatches& pair : taken.pairs) got.emplace(pair.image_id1, pair.image_id2);
    EXPECT_EQ(got, expected) << "frames up to " << batch_end;
    // By later frame.
    EXPECT_TRUE(std::is_sorted(taken.pairs.begin(), taken.pairs.end(),
                               [&](const auto& x, const auto& y) { return later(x) < later(y); }));
    num_taken += taken.pairs.size();
    batch_begin = batch_end;
  }
  producer.join();
  EXPECT_EQ(num_taken, pairs.size());
}

MapperImage Frame(image_t id) {
  MapperImage frame;
  frame.image_id = id;
  frame.timestamp_ns = StampOf(id);
  frame.name = std::to_string(id) + ".png";
  return frame;
}

// Frames added as the producer reaches them: a batch is handed over once
// its frames and their pairs are in, and once it is known whether frames
// follow; the stream's end makes the last batch a short one.
TEST(VerifiedPairStream, FramesArriveWithTheirPairs) {
  VerifiedPairStream stream;
  EXPECT_FALSE(stream.frames_up_front());
  std::atomic<int> frames_added{0};
  std::thread producer([&] {
    for (image_t id = 1; id <= 11; ++id) {
      std::this_thread::sleep_for(std::chrono::microseconds(300));
      // Set before the frame is added, whose lock orders it before the
      // consumer's wake-up.
      frames_added = static_cast<int>(id);
      stream.AddFrame(Frame(id));
      std::vector<ImagePairMatches> pairs;
      if (id > 1) pairs.push_back(Pair(id - 1, id));
      if (id > 4) pairs.push_back(Pair(id, id - 4));
      stream.Add(std::move(pairs), StampOf(id + 1));
    }
    stream.Close();
  });
  VerifiedPairStream::Taken taken = stream.Take(5);
  // It waited for the frame after the batch (is there one?).
  EXPECT_GE(frames_added.load(), 6);
  ASSERT_EQ(taken.frames.size(), 5u);
  EXPECT_EQ(taken.frames.front().image_id, 1u);
  EXPECT_EQ(taken.frames.back().image_id, 5u);
  EXPECT_EQ(taken.pairs.size(), 5u);  // (1,2) .. (4,5), (5,1)
  EXPECT_FALSE(taken.last);
  taken = stream.Take(10);
  ASSERT_EQ(taken.frames.size(), 5u);
  EXPECT_EQ(taken.frames.front().image_id, 6u);
  EXPECT_EQ(taken.pairs.size(), 10u);
  EXPECT_FALSE(taken.last);
  taken = stream.Take(15);
  producer.join();
  ASSERT_EQ(taken.frames.size(), 1u);
  EXPECT_EQ(taken.frames.front().image_id, 11u);
  EXPECT_EQ(taken.end, 11u);
  EXPECT_TRUE(taken.last);
  EXPECT_EQ(taken.pairs.size(), 2u);
}

TEST(VerifiedPairStream, AStreamedFrameMustFollowTheLast) {
  VerifiedPairStream stream;
  stream.AddFrame(Frame(3));
  EXPECT_THAT([&] { stream.AddFrame(Frame(2)); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("does not follow the last frame")));
  MapperImage again = Frame(3);
  again.timestamp_ns = StampOf(4);
  EXPECT_THAT([&] { stream.AddFrame(again); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("added twice")));
  // A pair of a frame not added yet.
  EXPECT_THAT([&] { stream.Add({Pair(3, 4)}, StampOf(4)); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("unknown image id 4")));
}

TEST(VerifiedPairStream, TheProducersFailureReachesTheConsumer) {
  VerifiedPairStream stream = MakeStream(3);
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    stream.Fail("frame 2: no descriptors");
  });
  EXPECT_THAT([&] { stream.Take(3); },
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

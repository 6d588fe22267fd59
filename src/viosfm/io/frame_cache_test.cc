#include "viosfm/io/frame_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

#include "viosfm/io/image_io.h"
#include "viosfm/util/errors.h"
#include "viosfm/util/testing.h"

namespace viosfm {
namespace {

namespace fs = std::filesystem;

fs::path WriteImage(const fs::path& folder, const std::string& name, uint8_t value) {
  GreyImage image(8, 4, value);
  image.at(3, 2) = static_cast<uint8_t>(value + 1);
  const fs::path path = folder / name;
  WriteGreyPng(path, image);
  return path;
}

TEST(FrameCacheTest, EachImageIsDecodedOnceWhenKept) {
  const fs::path folder = testing::MakeScratchFolder("frame_cache_once");
  const fs::path a = WriteImage(folder, "a.png", 10);
  const fs::path b = WriteImage(folder, "b.png", 20);
  FrameCache cache(1 << 20);
  EXPECT_EQ(cache.Read(a, /*keep=*/true)->at(3, 2), 11);
  EXPECT_EQ(cache.Read(b, /*keep=*/true)->at(0, 0), 20);
  const auto again = cache.Take(a);  // from the cache
  EXPECT_EQ(again->at(3, 2), 11);
  EXPECT_EQ(again->at(0, 0), 10);
  const auto b_taken = cache.Take(b);
  EXPECT_EQ(b_taken->at(3, 2), 21);
  FrameCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.decodes, 2u);
  EXPECT_EQ(counts.reuses, 2u);
  EXPECT_EQ(counts.peak_bytes, 64u);  // two 8 x 4 images
  // Taken images are released: a third ask decodes again.
  cache.Take(a);
  EXPECT_EQ(cache.counts().decodes, 3u);
}

TEST(FrameCacheTest, BudgetAndRetainOnlyBoundWhatIsHeld) {
  const fs::path folder = testing::MakeScratchFolder("frame_cache_budget");
  const fs::path a = WriteImage(folder, "a.png", 1);
  const fs::path b = WriteImage(folder, "b.png", 2);
  const fs::path c = WriteImage(folder, "c.png", 3);
  FrameCache cache(64);  // room for two 32-byte images
  cache.Read(a, true);
  cache.Read(b, true);
  cache.Read(c, true);  // no room: not kept
  EXPECT_EQ(cache.counts().not_kept, 1u);
  cache.RetainOnly({b});
  cache.Take(a);  // released by RetainOnly: decoded again
  cache.Take(b);  // held
  cache.Take(c);  // never kept
  const FrameCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.decodes, 5u);
  EXPECT_EQ(counts.reuses, 1u);
  EXPECT_EQ(counts.peak_bytes, 64u);
  // After RetainOnly only the retained paths are kept.
  cache.Read(a, true);
  cache.Read(b, true);
  cache.Take(a);  // not kept: decoded again
  cache.Take(b);  // kept
  EXPECT_EQ(cache.counts().decodes, 8u);
  EXPECT_EQ(cache.counts().reuses, 2u);
}

TEST(FrameCacheTest, TakeAfterReadWaitsForTheReaderAndStopsWhenItIsDone) {
  const fs::path folder = testing::MakeScratchFolder("frame_cache_after_read");
  const fs::path a = WriteImage(folder, "a.png", 10);
  const fs::path b = WriteImage(folder, "b.png", 20);
  const fs::path never = WriteImage(folder, "never.png", 30);
  FrameCache cache(1 << 20);
  std::shared_ptr<const GreyImage> taken_a, taken_b, taken_never;
  std::thread follower([&] {
    taken_a = cache.TakeAfterRead(a);
    taken_b = cache.TakeAfterRead(b);
    taken_never = cache.TakeAfterRead(never);  // never read: waits for StopWaiting
  });
  cache.Read(a, /*keep=*/true);
  cache.Read(b, /*keep=*/true);
  cache.StopWaiting();
  follower.join();
  ASSERT_NE(taken_a, nullptr);
  ASSERT_NE(taken_b, nullptr);
  EXPECT_EQ(taken_a->at(3, 2), 11);
  EXPECT_EQ(taken_b->at(3, 2), 21);
  EXPECT_EQ(taken_never, nullptr);
  const FrameCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.decodes, 2u);  // each read image decoded once, taken from the cache
  EXPECT_EQ(counts.reuses, 2u);
  // Read paths stay read after StopWaiting: taken (decoded again, released before).
  EXPECT_NE(cache.TakeAfterRead(a), nullptr);
  EXPECT_EQ(cache.TakeAfterRead(never), nullptr);
}

// A frame preloaded (the texture probe) is held, but a follower still waits
// for the reader's own Read, which then finds it held: the reader and the
// follower share the one decode.
TEST(FrameCacheTest, PreloadedFrameIsTakenAfterTheReadersReadNotBefore) {
  const fs::path folder = testing::MakeScratchFolder("frame_cache_preload");
  const fs::path a = WriteImage(folder, "a.png", 10);
  FrameCache cache(1 << 20);
  EXPECT_EQ(cache.Preload(a)->at(3, 2), 11);
  std::atomic<bool> taken{false};
  std::shared_ptr<const GreyImage> taken_a;
  std::thread follower([&] {
    taken_a = cache.TakeAfterRead(a);
    taken = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(taken);  // preloaded, not read: the follower waits
  EXPECT_EQ(cache.Read(a, /*keep=*/true)->at(3, 2), 11);
  follower.join();
  ASSERT_NE(taken_a, nullptr);
  EXPECT_EQ(taken_a->at(3, 2), 11);
  const FrameCache::Counts counts = cache.counts();
  EXPECT_EQ(counts.decodes, 1u);
  EXPECT_EQ(counts.reuses, 2u);  // the reader's Read and the follower's Take
}

TEST(FrameCacheTest, UnreadableFileIsAnInputError) {
  FrameCache cache(1 << 20);
  EXPECT_THROW(cache.Read("/nonexistent/x.png", true), InputError);
}

}  // namespace
}  // namespace viosfm

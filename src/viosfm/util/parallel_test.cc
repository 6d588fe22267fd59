#include "viosfm/util/parallel.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace viosfm {
namespace {

TEST(Parallel, EveryIndexExactlyOnce) {
  for (int threads : {1, 2, 5}) {
    std::vector<std::atomic<int>> hits(1000);
    ParallelFor(1000, threads, [&](int64_t i, int thread_index) {
      EXPECT_LT(thread_index, NumThreadsFor(1000, threads));
      ++hits[i];
    });
    for (const auto& hit : hits) ASSERT_EQ(hit.load(), 1);
  }
  std::vector<std::atomic<int>> covered(103);
  ParallelForChunks(103, 2, 10, [&](int64_t begin, int64_t end) {
    EXPECT_LE(end - begin, 10);
    for (int64_t i = begin; i < end; ++i) ++covered[i];
  });
  for (const auto& hit : covered) ASSERT_EQ(hit.load(), 1);
  ParallelFor(0, 2, [](int64_t, int) { FAIL() << "no index expected"; });
}

TEST(Parallel, RethrowsTheBodysException) {
  EXPECT_THROW(ParallelFor(100, 2,
                           [](int64_t i, int) {
                             if (i == 37) throw std::runtime_error("body failed");
                           }),
               std::runtime_error);
}

}  // namespace
}  // namespace viosfm

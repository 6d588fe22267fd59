#include "viosfm/util/progress.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace viosfm {
namespace {

TEST(ProgressBar, FormatsLine) {
  EXPECT_EQ(ProgressBar::FormatLine("SIFT", 5, 10, 2.0, 10),
            "SIFT [#####.....] 5/10 (2.5/s, 2s, ETA 2s)");
  EXPECT_EQ(ProgressBar::FormatLine("SIFT", 10, 10, 65.0, 0), "SIFT 10/10 (0.2/s, 1m05s)");
}

TEST(ProgressBar, CountsFromManyThreads) {
  ProgressBar bar("count", 4000, ProgressBar::Mode::kNever);
  EXPECT_FALSE(bar.drawing());
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&bar] {
      for (int i = 0; i < 1000; ++i) bar.Update();
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(bar.done(), 4000);
}

}  // namespace
}  // namespace viosfm

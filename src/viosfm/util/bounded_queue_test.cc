#include "viosfm/util/bounded_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace viosfm {
namespace {

TEST(BoundedQueueTest, HandsOverEveryItemInOrder) {
  BoundedQueue<int> queue(3);
  std::thread producer([&] {
    for (int i = 0; i < 1000; ++i) ASSERT_TRUE(queue.Push(i));
    queue.Close();
  });
  std::vector<int> received;
  while (std::optional<int> item = queue.Pop()) received.push_back(*item);
  producer.join();
  ASSERT_EQ(received.size(), 1000u);
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(received[i], i);
}

TEST(BoundedQueueTest, AProducerWaitsForRoom) {
  BoundedQueue<int> queue(2);
  std::atomic<int> pushed{0};
  std::thread producer([&] {
    for (int i = 0; i < 5; ++i) {
      queue.Push(i);
      ++pushed;
    }
  });
  // The third push waits until an item is taken.
  while (pushed < 2) std::this_thread::yield();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(pushed.load(), 2);
  EXPECT_EQ(queue.Pop(), 0);
  for (int i = 1; i < 5; ++i) EXPECT_EQ(queue.Pop(), i);
  producer.join();
  EXPECT_EQ(pushed.load(), 5);
}

TEST(BoundedQueueTest, CloseReleasesAWaitingProducerAndEmptiesThenEnds) {
  BoundedQueue<int> queue(1);
  ASSERT_TRUE(queue.Push(7));
  std::atomic<bool> refused{false};
  std::thread producer([&] { refused = !queue.Push(8); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  queue.Close();
  producer.join();
  EXPECT_TRUE(refused.load());
  EXPECT_EQ(queue.Pop(), 7);
  EXPECT_EQ(queue.Pop(), std::nullopt);
}

TEST(BoundedQueueTest, AbortDropsWhatWasQueued) {
  BoundedQueue<int> queue(4);
  queue.Push(1);
  queue.Push(2);
  queue.Abort();
  EXPECT_EQ(queue.Pop(), std::nullopt);
  EXPECT_FALSE(queue.Push(3));
}

}  // namespace
}  // namespace viosfm

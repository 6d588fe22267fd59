// A minimal parallel loop over the indices [0, count), used by the matchers.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace viosfm::matching_internal {

// -1 (or 0): all hardware threads; otherwise the number given (at least 1).
inline int ResolveNumThreads(int num_threads) {
  if (num_threads > 0) return num_threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Calls body(index, thread_index) for every index, spreading the indices over
// up to `num_threads` threads (each index exactly once; thread_index is in
// [0, threads used)). The first exception a body throws is rethrown here.
template <typename Body>
void ParallelFor(int64_t count, int num_threads, Body&& body) {
  const int threads = static_cast<int>(std::min<int64_t>(ResolveNumThreads(num_threads), count));
  if (threads <= 1) {
    for (int64_t i = 0; i < count; ++i) body(i, 0);
    return;
  }
  std::atomic<int64_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](int thread_index) {
    try {
      for (int64_t i = next++; i < count; i = next++) body(i, thread_index);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = count;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

// The number of threads ParallelFor(count, num_threads, ...) uses.
inline int NumThreadsFor(int64_t count, int num_threads) {
  return static_cast<int>(
      std::max<int64_t>(1, std::min<int64_t>(ResolveNumThreads(num_threads), count)));
}

}  // namespace viosfm::matching_internal

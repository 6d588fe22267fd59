// Minimal parallel loops over index ranges, on std::thread. The calling
// thread is one of the workers; the first exception a body throws stops the
// hand-out of further work and is rethrown to the caller. Results must not
// depend on which thread runs which index (every caller's tests check that
// 1 and several threads give identical output).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace viosfm {

// num_threads <= 0: all hardware threads; otherwise the number given.
inline int ResolveNumThreads(int num_threads) {
  if (num_threads > 0) return num_threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// The number of threads ParallelFor(count, num_threads, ...) uses.
inline int NumThreadsFor(int64_t count, int num_threads) {
  return static_cast<int>(
      std::max<int64_t>(1, std::min<int64_t>(ResolveNumThreads(num_threads), count)));
}

// Calls body(index, thread_index) once for every index in [0, count), with
// indices handed out one at a time to up to `num_threads` threads;
// thread_index is in [0, NumThreadsFor(count, num_threads)).
template <typename Body>
void ParallelFor(int64_t count, int num_threads, Body&& body) {
  if (count <= 0) return;
  const int threads = NumThreadsFor(count, num_threads);
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
  pool.reserve(threads - 1);
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

// Calls body(begin, end) on disjoint chunks of `chunk_size` indices covering
// [0, count), handed out to up to `num_threads` threads.
inline void ParallelForChunks(int64_t count, int num_threads, int64_t chunk_size,
                              const std::function<void(int64_t, int64_t)>& body) {
  if (count <= 0) return;
  chunk_size = std::max<int64_t>(1, chunk_size);
  const int64_t num_chunks = (count + chunk_size - 1) / chunk_size;
  ParallelFor(num_chunks, num_threads, [&](int64_t chunk, int /*thread_index*/) {
    const int64_t begin = chunk * chunk_size;
    body(begin, std::min(count, begin + chunk_size));
  });
}

}  // namespace viosfm

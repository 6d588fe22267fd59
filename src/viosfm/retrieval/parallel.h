// A minimal parallel loop for the retrieval layer.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <thread>
#include <vector>

namespace viosfm::retrieval_internal {

// Number of worker threads for `num_threads` (<= 0: all hardware threads).
inline int ResolveNumThreads(int num_threads) {
  if (num_threads > 0) return num_threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Calls body(begin, end) on disjoint chunks covering [0, count), dynamically
// handed out to up to `num_threads` threads (the calling thread is one of
// them). Rethrows the first exception a chunk threw. The result must not
// depend on which thread runs which chunk.
inline void ParallelForChunks(int64_t count, int num_threads, int64_t chunk_size,
                              const std::function<void(int64_t, int64_t)>& body) {
  if (count <= 0) return;
  chunk_size = std::max<int64_t>(1, chunk_size);
  const int64_t num_chunks = (count + chunk_size - 1) / chunk_size;
  const int workers =
      static_cast<int>(std::min<int64_t>(ResolveNumThreads(num_threads), num_chunks));
  if (workers <= 1) {
    body(0, count);
    return;
  }
  std::atomic<int64_t> next_chunk{0};
  std::vector<std::exception_ptr> errors(workers);
  auto work = [&](int worker) {
    try {
      for (int64_t chunk = next_chunk++; chunk < num_chunks; chunk = next_chunk++) {
        const int64_t begin = chunk * chunk_size;
        body(begin, std::min(count, begin + chunk_size));
      }
    } catch (...) {
      errors[worker] = std::current_exception();
      next_chunk = num_chunks;
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);
  for (int worker = 1; worker < workers; ++worker) threads.emplace_back(work, worker);
  work(0);
  for (std::thread& thread : threads) thread.join();
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

}  // namespace viosfm::retrieval_internal

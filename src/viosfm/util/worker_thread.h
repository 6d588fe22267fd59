// A thread whose exception is kept for the thread that joins it.
#pragma once

#include <atomic>
#include <exception>
#include <thread>
#include <utility>

namespace viosfm {

class Worker {
 public:
  Worker() = default;
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;
  ~Worker() { Join(); }

  template <class Body>
  void Start(Body body) {
    thread_ = std::thread([this, body = std::move(body)]() mutable {
      try {
        body();
      } catch (...) {
        error_ = std::current_exception();
        failed_ = true;
      }
    });
  }
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  // Joins, then rethrows the thread's exception.
  void JoinAndRethrow() {
    Join();
    if (error_) std::rethrow_exception(error_);
  }
  // The thread has ended with an exception (any thread may ask).
  bool failed() const { return failed_; }

 private:
  std::thread thread_;
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
};

}  // namespace viosfm

// Wall-clock timer for stage timings (seconds, steady clock), and the
// process's CPU time.
#pragma once

#include <chrono>
#include <string>

namespace viosfm {

class Timer {
 public:
  Timer() { Start(); }
  void Start();
  void Pause();
  void Resume();
  // Seconds accumulated while running.
  double ElapsedSeconds() const;

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
  double accumulated_seconds_ = 0.0;
  bool running_ = false;
};

// Logs "<name>: <seconds> s" at INFO when it goes out of scope.
class ScopedTimer {
 public:
  explicit ScopedTimer(std::string name) : name_(std::move(name)) {}
  ~ScopedTimer();
  double ElapsedSeconds() const { return timer_.ElapsedSeconds(); }

 private:
  std::string name_;
  Timer timer_;
};

// CPU time the process has used so far (user + system, every thread), s.
double ProcessCpuSeconds();

}  // namespace viosfm

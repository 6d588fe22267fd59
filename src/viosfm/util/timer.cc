#include "viosfm/util/timer.h"

#include <ctime>
#include <iomanip>

#include "viosfm/util/logging.h"

namespace viosfm {

void Timer::Start() {
  accumulated_seconds_ = 0.0;
  start_ = Clock::now();
  running_ = true;
}

void Timer::Pause() {
  if (!running_) return;
  accumulated_seconds_ += std::chrono::duration<double>(Clock::now() - start_).count();
  running_ = false;
}

void Timer::Resume() {
  if (running_) return;
  start_ = Clock::now();
  running_ = true;
}

double Timer::ElapsedSeconds() const {
  double seconds = accumulated_seconds_;
  if (running_) seconds += std::chrono::duration<double>(Clock::now() - start_).count();
  return seconds;
}

double ProcessCpuSeconds() {
  timespec spec{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &spec);
  return static_cast<double>(spec.tv_sec) + 1e-9 * static_cast<double>(spec.tv_nsec);
}

ScopedTimer::~ScopedTimer() {
  VIOSFM_LOG(INFO) << name_ << ": " << std::fixed << std::setprecision(3) << timer_.ElapsedSeconds()
                   << " s";
}

}  // namespace viosfm

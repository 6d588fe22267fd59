// A progress bar for long loops, drawn on stderr.
//
// On a terminal it redraws one line (label, bar, count, rate, ETA) at most
// every 100 ms. When stderr is not a terminal (CI, a log file) it stays quiet
// and only logs one summary line when finished. Update() is thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "viosfm/util/timer.h"

namespace viosfm {

class ProgressBar {
 public:
  enum class Mode { kAuto, kAlways, kNever };

  ProgressBar(std::string label, int64_t total, Mode mode = Mode::kAuto);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // Adds `count` finished items.
  void Update(int64_t count = 1);
  // Marks the loop done (also called by the destructor).
  void Finish();

  int64_t done() const { return done_.load(); }
  bool drawing() const { return draw_; }

  // The line drawn for `done` of `total` items after `seconds`.
  static std::string FormatLine(const std::string& label, int64_t done, int64_t total,
                                double seconds, int width);

 private:
  void Draw(bool final_line);

  std::string label_;
  int64_t total_;
  bool draw_;
  bool finished_ = false;
  std::atomic<int64_t> done_{0};
  std::mutex mutex_;
  Timer timer_;
  double last_draw_seconds_ = -1.0;
};

}  // namespace viosfm

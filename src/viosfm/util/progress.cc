#include "viosfm/util/progress.h"

#include <unistd.h>

#include <cstdio>
#include <iomanip>
#include <sstream>

#include "viosfm/util/logging.h"

namespace viosfm {
namespace {

std::string FormatDuration(double seconds) {
  if (seconds < 0) seconds = 0;
  const int64_t s = static_cast<int64_t>(seconds + 0.5);
  std::ostringstream out;
  if (s >= 3600) out << s / 3600 << "h";
  if (s >= 60) out << std::setw(s >= 3600 ? 2 : 1) << std::setfill('0') << (s / 60) % 60 << "m";
  out << std::setw(s >= 60 ? 2 : 1) << std::setfill('0') << s % 60 << "s";
  return out.str();
}

}  // namespace

ProgressBar::ProgressBar(std::string label, int64_t total, Mode mode)
    : label_(std::move(label)), total_(total) {
  switch (mode) {
    case Mode::kAuto: draw_ = isatty(STDERR_FILENO) == 1; break;
    case Mode::kAlways: draw_ = true; break;
    case Mode::kNever: draw_ = false; break;
  }
}

ProgressBar::~ProgressBar() {
  Finish();
}

void ProgressBar::Update(int64_t count) {
  done_ += count;
  if (!draw_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  const double now = timer_.ElapsedSeconds();
  if (last_draw_seconds_ >= 0 && now - last_draw_seconds_ < 0.1) return;
  last_draw_seconds_ = now;
  Draw(false);
}

void ProgressBar::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (draw_) {
    Draw(true);
    LogToFileOnly(LogLevel::kINFO,
                  FormatLine(label_, done_.load(), total_, timer_.ElapsedSeconds(), 0));
  } else {
    VIOSFM_LOG(INFO) << FormatLine(label_, done_.load(), total_, timer_.ElapsedSeconds(), 0);
  }
}

void ProgressBar::Draw(bool final_line) {
  const std::string line = FormatLine(label_, done_.load(), total_, timer_.ElapsedSeconds(), 30);
  std::fprintf(stderr, "\r%s\033[K%s", line.c_str(), final_line ? "\n" : "");
  std::fflush(stderr);
}

std::string ProgressBar::FormatLine(const std::string& label, int64_t done, int64_t total,
                                    double seconds, int width) {
  std::ostringstream out;
  out << label << " ";
  const double fraction = total > 0 ? std::min(1.0, static_cast<double>(done) / total) : 1.0;
  if (width > 0) {
    const int filled = static_cast<int>(fraction * width + 0.5);
    out << "[" << std::string(filled, '#') << std::string(width - filled, '.') << "] ";
  }
  out << done << "/" << total;
  const double rate = seconds > 0 ? done / seconds : 0.0;
  out << std::fixed << std::setprecision(1) << " (" << rate << "/s, " << FormatDuration(seconds);
  if (done > 0 && done < total) out << ", ETA " << FormatDuration((total - done) / rate);
  out << ")";
  return out.str();
}

}  // namespace viosfm

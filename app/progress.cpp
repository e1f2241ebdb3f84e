#include "app/progress.h"

#include <algorithm>
#include <cstdio>

namespace tb {

ProgressLine::ProgressLine(bool enabled) : enabled_(enabled) {}

void ProgressLine::start(const std::string& label) {
  std::lock_guard lock(mutex_);
  label_ = label;
  started_ = last_ = std::chrono::steady_clock::now();
}

void ProgressLine::update(double fraction) {
  if (!enabled_) return;
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double f = std::clamp(fraction, 0.0, 1.0);
  const int width = 30, filled = static_cast<int>(f * width);
  const double elapsed = std::chrono::duration<double>(now - started_).count();
  std::fprintf(stderr, "\r  %-48.48s [%.*s%*s] %5.1f%%  %6.1fs", label_.c_str(), filled,
               "##############################", width - filled, "", 100 * f, elapsed);
  std::fflush(stderr);
}

void ProgressLine::finish() {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  std::fprintf(stderr, "\r%100s\r", "");
  std::fflush(stderr);
}

}  // namespace tb

// A one-line progress display on stderr for long runs: redrawn in place on a terminal,
// throttled, safe to call from worker threads.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace tb {

class ProgressLine {
 public:
  explicit ProgressLine(bool enabled);
  void start(const std::string& label);
  void update(double fraction);  // thread-safe, throttled to ~10 Hz
  void finish();                 // clears the line

 private:
  bool enabled_;
  std::mutex mutex_;
  std::string label_;
  std::chrono::steady_clock::time_point started_, last_;
};

}  // namespace tb

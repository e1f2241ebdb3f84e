// NaN and Inf never enter a film silently (ARCHITECTURE.md "Numbers"; STYLE.md): every rejected
// sample is counted, and the first few are kept with their pixel and sample index so that a
// run can be replayed at that sample.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"

namespace tb {

struct NonFiniteSample {
  Vec2 raster{0.0};
  int64_t pixel_x = -1, pixel_y = -1;  // -1 when the raster position itself is not finite
  uint64_t sample_index = 0;           // as passed by the caller (its stream index)
  Rgb value{0.0};
  bool splat = false;                  // splat() rather than add_sample()
  std::string describe() const;
};

// The record for a rejected value at a raster position (pixel = floor of a finite position).
NonFiniteSample make_nonfinite_sample(const Vec2& raster, const Rgb& value, uint64_t sample_index, bool splat);

class NonFiniteLog {
 public:
  static constexpr size_t kKept = 16;

  void add(const NonFiniteSample& s) {
    ++count_;
    if (kept_.size() < kKept) kept_.push_back(s);
  }
  // Appends another log (merged in a fixed order by the callers, so the kept records are
  // deterministic).
  void merge(const NonFiniteLog& o) {
    count_ += o.count_;
    for (const auto& s : o.kept_)
      if (kept_.size() < kKept) kept_.push_back(s);
  }
  int64_t count() const { return count_; }
  const std::vector<NonFiniteSample>& kept() const { return kept_; }
  // "3 non-finite samples rejected; first: pixel (4, 7) sample 12 value (nan, 0, 0) [add_sample]"
  std::string summary() const;

 private:
  int64_t count_ = 0;
  std::vector<NonFiniteSample> kept_;
};

}  // namespace tb

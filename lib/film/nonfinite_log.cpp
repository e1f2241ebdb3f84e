#include "lib/film/nonfinite_log.h"

#include <cmath>

#include <fmt/format.h>

namespace tb {

std::string NonFiniteSample::describe() const {
  return fmt::format("pixel ({}, {}) raster ({}, {}) sample {} value ({}, {}, {}) [{}]", pixel_x, pixel_y, raster.x,
                     raster.y, sample_index, value.r, value.g, value.b, splat ? "splat" : "add_sample");
}

NonFiniteSample make_nonfinite_sample(const Vec2& raster, const Rgb& value, uint64_t sample_index, bool splat) {
  NonFiniteSample s;
  s.raster = raster;
  if (is_finite(raster)) {
    s.pixel_x = static_cast<int64_t>(std::floor(raster.x));
    s.pixel_y = static_cast<int64_t>(std::floor(raster.y));
  }
  s.sample_index = sample_index;
  s.value = value;
  s.splat = splat;
  return s;
}

std::string NonFiniteLog::summary() const {
  if (count_ == 0) return "no non-finite samples";
  return fmt::format("{} non-finite samples rejected; first: {}", count_, kept_.front().describe());
}

}  // namespace tb

#include "lib/film/film.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "lib/core/parallel.h"

namespace tb {

Film::Film(int width, int height, std::shared_ptr<const Filter> filter)
    : width_(width),
      height_(height),
      filter_(std::move(filter)),
      pass_({0, 0, width, height}, {0, 0, width, height}, filter_),
      pass_splat_(size_t(std::max(width, 0)) * size_t(std::max(height, 0)), Rgb(0.0)),
      welch_(width, height),
      direct_splats_(width, height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("Film: empty resolution");
}

bool Film::add_sample(const Vec2& raster, const Rgb& L, uint64_t sample_index) {
  if (!is_finite(raster) || !is_finite(L)) {
    nonfinite_.add(make_nonfinite_sample(raster, L, sample_index, false));
    return false;
  }
  return pass_.add_sample(raster, L, sample_index);
}

bool Film::splat(const Vec2& raster, const Rgb& v, uint64_t sample_index) {
  direct_splats_.clear();
  const bool kept = direct_splats_.splat(raster, v, sample_index);
  merge_splats(direct_splats_);
  return kept;
}

FilmTile Film::make_tile(const PixelBounds& p) const {
  // A sample in pixel x reaches pixel centres within the radius: at most ceil(r + 0.5) over.
  const Vec2 r = filter_->radius();
  const int gx = static_cast<int>(std::ceil(r.x + 0.5)), gy = static_cast<int>(std::ceil(r.y + 0.5));
  const PixelBounds store{std::max(0, p.x0 - gx), std::max(0, p.y0 - gy), std::min(width_, p.x1 + gx),
                          std::min(height_, p.y1 + gy)};
  return FilmTile(p, store, filter_);
}

void Film::merge_tile(const FilmTile& tile) {
  pass_.merge(tile);  // the whole-image pass tile's own log is unused: the film keeps nonfinite_
  nonfinite_.merge(tile.nonfinite());
}

void Film::merge_tiles(std::span<const FilmTile> tiles) {
  constexpr int kBand = 16;  // rows per task
  parallel_for(size_t((height_ + kBand - 1) / kBand), [&](size_t band) {
    const int y0 = int(band) * kBand, y1 = std::min(height_, y0 + kBand);
    for (const FilmTile& t : tiles)
      if (t.store().y0 < y1 && t.store().y1 > y0) pass_.merge_rows(t, y0, y1);
  });
  for (const FilmTile& t : tiles) nonfinite_.merge(t.nonfinite());
}

void Film::merge_splats(const SplatBuffer& s) {
  for (const auto& e : s.entries()) pass_splat_[e.pixel] += e.value;
  pass_splats_ += int64_t(s.entries().size());
  nonfinite_.merge(s.nonfinite());
  splats_outside_ += s.outside();
}

void Film::end_pass(double splat_scale) {
  if (pass_splats_ > 0 && splat_scale == 0.0)
    throw std::logic_error("Film::end_pass: the pass holds splats but splat_scale is 0 (use P / N for N paths)");
  if (observer_) observed_.assign(welch_.pixels(), Rgb(0.0));
  // Pixels are independent: rows in parallel, empty pixels counted per row and summed.
  std::vector<int64_t> empty(size_t(height_), 0);
  parallel_for(size_t(height_), [&](size_t row) {
    const int y = int(row);
    for (int x = 0; x < width_; ++x) {
      const size_t i = size_t(y) * size_t(width_) + size_t(x);
      const double w = pass_.weight_sum(x, y);
      Rgb v = splat_scale * pass_splat_[i];
      if (w > 0.0)
        v += pass_.weighted_sum(x, y) / w;
      else
        ++empty[row];
      welch_.add(i, v);
      if (observer_) observed_[i] = v;
    }
  });
  for (const int64_t e : empty) empty_pixel_passes_ += e;
  if (observer_) observer_(observed_);
  pass_.clear();
  std::fill(pass_splat_.begin(), pass_splat_.end(), Rgb(0.0));
  pass_splats_ = 0;
  ++passes_;
}

Rgb Film::pixel(int x, int y) const { return welch_.mean(size_t(y) * size_t(width_) + size_t(x)); }

std::vector<Rgb> Film::mean_image() const {
  std::vector<Rgb> out(welch_.pixels());
  for (size_t i = 0; i < out.size(); ++i) out[i] = welch_.mean(i);
  return out;
}

}  // namespace tb

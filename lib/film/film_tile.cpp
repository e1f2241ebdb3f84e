#include "lib/film/film_tile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tb {

FilmTile::FilmTile(PixelBounds pixels, PixelBounds store, std::shared_ptr<const Filter> filter)
    : pixels_(pixels), store_(store), filter_(std::move(filter)) {
  if (!filter_) throw std::invalid_argument("FilmTile: no filter");
  const auto* box = dynamic_cast<const BoxFilter*>(filter_.get());
  unit_box_ = box && box->radius() == Vec2(0.5);
  if (store_.width() < 0 || store_.height() < 0) throw std::invalid_argument("FilmTile: negative bounds");
  wl_.assign(static_cast<size_t>(store_.area()), Rgb(0.0));
  w_.assign(static_cast<size_t>(store_.area()), 0.0);
}

bool FilmTile::add_sample(const Vec2& raster, const Rgb& L, uint64_t sample_index) {
  if (!is_finite(raster) || !is_finite(L)) {
    reject(raster, L, sample_index);
    return false;
  }
  if (unit_box_ && raster.x >= 0.0 && raster.y >= 0.0) {
    // Box of radius 0.5 and a position p >= 0: the loop of add_filtered gives weight 1 to pixel
    // floor(p) on each axis and 0 to every other pixel, so only that pixel is touched. Per axis,
    // with c = i + 0.5 (exact): for i = floor(p), p - c lies in [-0.5, 0.5) and its rounding
    // keeps it there (-0.5 is a float, rounding is monotone, and p - c is exact by Sterbenz's
    // lemma whenever it is near 0.5); for i < floor(p), p - c >= 0.5; for i > floor(p), p - c <
    // -0.5 and is exact by Sterbenz when near -0.5 (i >= 1). The loop's bounds ceil(p - 0.5 - 0.5)
    // <= floor(p) <= floor(p - 0.5 + 0.5) hold in float arithmetic by monotone rounding, so it
    // does visit floor(p). The sums get 1 * L == L and 1, bit for bit those of the loop.
    // For p >= 0, floor(p) is in [x0, x1) iff p is (integer bounds), and then the int
    // conversion truncates to floor(p).
    if (raster.x >= store_.x0 && raster.x < store_.x1 && raster.y >= store_.y0 && raster.y < store_.y1)
      accumulate(index(static_cast<int>(raster.x), static_cast<int>(raster.y)), 1.0, L);
    return true;
  }
  add_filtered(raster, L);
  return true;
}

void FilmTile::reject(const Vec2& raster, const Rgb& L, uint64_t sample_index) {
  nonfinite_.add(make_nonfinite_sample(raster, L, sample_index, false));
}

void FilmTile::add_filtered(const Vec2& raster, const Rgb& L) {
  // Pixels whose centre (i + 0.5, j + 0.5) is within the radius (pbrt-v3 Sec. 7.9.2).
  const Vec2 r = filter_->radius();
  // Clamped in double before the conversion, so far-away positions cannot overflow an int.
  const auto to_int = [](double v, int lo, int hi) {
    return static_cast<int>(std::clamp(v, double(lo) - 1.0, double(hi) + 1.0));
  };
  const int ix0 = std::max(store_.x0, to_int(std::ceil(raster.x - 0.5 - r.x), store_.x0, store_.x1));
  const int ix1 = std::min(store_.x1 - 1, to_int(std::floor(raster.x - 0.5 + r.x), store_.x0, store_.x1));
  const int iy0 = std::max(store_.y0, to_int(std::ceil(raster.y - 0.5 - r.y), store_.y0, store_.y1));
  const int iy1 = std::min(store_.y1 - 1, to_int(std::floor(raster.y - 0.5 + r.y), store_.y0, store_.y1));
  for (int y = iy0; y <= iy1; ++y)
    for (int x = ix0; x <= ix1; ++x) {
      const double w = filter_->eval(raster - Vec2(x + 0.5, y + 0.5));
      if (w == 0.0) continue;
      accumulate(index(x, y), w, L);
    }
}

void FilmTile::merge(const FilmTile& o) {
  merge_rows(o, o.store_.y0, o.store_.y1);
  nonfinite_.merge(o.nonfinite_);
}

void FilmTile::merge_rows(const FilmTile& o, int y0, int y1) {
  for (int y = std::max(y0, o.store_.y0); y < std::min(y1, o.store_.y1); ++y)
    for (int x = o.store_.x0; x < o.store_.x1; ++x) {
      if (!store_.contains(x, y)) throw std::out_of_range("FilmTile::merge: tile outside the target");
      const size_t i = index(x, y), j = o.index(x, y);
      wl_[i] += o.wl_[j];
      w_[i] += o.w_[j];
    }
}

void FilmTile::clear() {
  std::fill(wl_.begin(), wl_.end(), Rgb(0.0));
  std::fill(w_.begin(), w_.end(), 0.0);
  nonfinite_ = {};
}

bool SplatBuffer::splat(const Vec2& raster, const Rgb& v, uint64_t sample_index) {
  if (!is_finite(raster) || !is_finite(v)) {
    nonfinite_.add(make_nonfinite_sample(raster, v, sample_index, true));
    return false;
  }
  const double fx = std::floor(raster.x), fy = std::floor(raster.y);
  if (fx < 0.0 || fy < 0.0 || fx >= width_ || fy >= height_) {
    ++outside_;
    return false;
  }
  entries_.push_back({static_cast<uint32_t>(static_cast<int64_t>(fy) * width_ + static_cast<int64_t>(fx)), v});
  return true;
}

}  // namespace tb

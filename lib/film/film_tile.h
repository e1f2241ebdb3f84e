// Accumulators that one task owns while sampling, merged into the film in a fixed order so that
// images are bit-identical whatever the number of threads (ARCHITECTURE.md "Numbers"):
//   FilmTile     filter-weighted sums (sum w L, sum w) over a pixel rectangle;
//   SplatBuffer  a list of (pixel, value) splats from light tracing / MCMC, kept in the order
//                they were made.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/film/filter.h"
#include "lib/film/nonfinite_log.h"

namespace tb {

// Half-open pixel rectangle [x0, x1) x [y0, y1).
struct PixelBounds {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  int64_t area() const { return static_cast<int64_t>(width()) * height(); }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

class FilmTile {
 public:
  // `pixels`: the pixels whose samples this tile takes; `store`: the pixels its filter
  // footprints may reach (pixels grown by the filter radius, clipped to the image).
  FilmTile(PixelBounds pixels, PixelBounds store, std::shared_ptr<const Filter> filter);

  // Adds L at a raster position with the filter's weights to every pixel in reach. A non-finite
  // L or position is rejected and logged with sample_index; returns false then.
  bool add_sample(const Vec2& raster, const Rgb& L, uint64_t sample_index);

  const PixelBounds& pixels() const { return pixels_; }
  const PixelBounds& store() const { return store_; }
  const Rgb& weighted_sum(int x, int y) const { return wl_[index(x, y)]; }
  double weight_sum(int x, int y) const { return w_[index(x, y)]; }
  const NonFiniteLog& nonfinite() const { return nonfinite_; }
  // Adds another tile's sums (of any bounds inside this tile's store) and log into this one.
  void merge(const FilmTile& other);
  // The sums of rows [y0, y1) of another tile only (its log is left out): tiles merged band by
  // band in parallel, each band taking the tiles in the same order, add to every pixel in the
  // order merge() would.
  void merge_rows(const FilmTile& other, int y0, int y1);
  void clear();

 private:
  size_t index(int x, int y) const {
    return static_cast<size_t>(y - store_.y0) * static_cast<size_t>(store_.width()) + static_cast<size_t>(x - store_.x0);
  }
  // The general case of add_sample (any filter; L and raster finite): every pixel in the
  // filter's reach; and the log of a rejected sample. Neither is inlined, so that the common
  // case (box fast path) keeps a short prologue.
  [[gnu::noinline]] void add_filtered(const Vec2& raster, const Rgb& L);
  [[gnu::noinline, gnu::cold]] void reject(const Vec2& raster, const Rgb& L, uint64_t sample_index);
  // Adds weight w and w L to the sums of store pixel i (the one accumulation of both paths of
  // add_sample).
  void accumulate(size_t i, double w, const Rgb& L) {
    wl_[i] += w * L;
    w_[i] += w;
  }
  PixelBounds pixels_, store_;
  std::shared_ptr<const Filter> filter_;
  // The filter is a BoxFilter of radius 0.5 (the default "box"): add_sample then takes its
  // one-pixel fast path instead of two virtual calls per pixel of the footprint.
  bool unit_box_ = false;
  std::vector<Rgb> wl_;
  std::vector<double> w_;
  NonFiniteLog nonfinite_;
};

class SplatBuffer {
 public:
  struct Entry {
    uint32_t pixel;  // y * width + x
    Rgb value;
  };
  SplatBuffer(int width, int height) : width_(width), height_(height) {}

  // Adds v to the pixel containing the raster position (the pixel's box, the h_j of
  // docs/camera.md). Non-finite values are rejected and logged; positions outside the image
  // are counted in outside() and dropped. Returns whether v was kept.
  bool splat(const Vec2& raster, const Rgb& v, uint64_t sample_index);

  const std::vector<Entry>& entries() const { return entries_; }
  const NonFiniteLog& nonfinite() const { return nonfinite_; }
  int64_t outside() const { return outside_; }
  void clear() {
    entries_.clear();
    nonfinite_ = {};
    outside_ = 0;
  }

 private:
  int width_, height_;
  std::vector<Entry> entries_;
  NonFiniteLog nonfinite_;
  int64_t outside_ = 0;
};

}  // namespace tb

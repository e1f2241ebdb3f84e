// The film: an image of RGB pixels in double, built from passes. During a pass, add_sample()
// accumulates filter-weighted radiance (pbrt-v3 Eq. 7.12: pixel = sum w L / sum w) and
// splat() accumulates light-tracing / MCMC contributions in the pixel that contains them.
// end_pass(splat_scale) turns every pixel's pass estimate
//     X_j = sum w L / sum w  +  splat_scale * sum splats
// into one Welch sample: the film keeps per pixel and channel the sum and sum of squares of
// the X_j and their count, so two films can be compared by Welch's t-test
// (validate/image_compare.h; Jung et al. 2020). For light tracing with N paths in a pass and
// the whole-image normalisation of We (docs/camera.md), splat_scale = P / N, P = pixel count.
//
// Threads: add_sample/splat on the film are not thread-safe. For parallel work use tiles and
// splat buffers (film_tile.h) merged in a fixed order (film_parallel.h): results are then
// bit-identical whatever the thread count.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "lib/film/film_tile.h"
#include "lib/film/filter.h"
#include "lib/film/welch_image.h"

namespace tb {

class Film {
 public:
  Film(int width, int height, std::shared_ptr<const Filter> filter = std::make_shared<BoxFilter>());

  int width() const { return width_; }
  int height() const { return height_; }
  int64_t pixel_count() const { return static_cast<int64_t>(width_) * height_; }
  const Filter& filter() const { return *filter_; }

  // Single-threaded accumulation into the current pass. Non-finite input is rejected and
  // logged with the pixel and sample index (nonfinite()); the return value says if it was kept.
  bool add_sample(const Vec2& raster, const Rgb& L, uint64_t sample_index);
  bool splat(const Vec2& raster, const Rgb& v, uint64_t sample_index);

  // A tile taking the samples of `pixels`, with storage for its filter footprint.
  FilmTile make_tile(const PixelBounds& pixels) const;
  void merge_tile(const FilmTile& tile);
  // merge_tile(tiles[0]), merge_tile(tiles[1]), ... with the same result bit for bit, in
  // parallel over bands of rows (every pixel still receives the tiles' sums in their order).
  void merge_tiles(std::span<const FilmTile> tiles);
  void merge_splats(const SplatBuffer& splats);

  // Closes the pass: one Welch sample per pixel (see above). Pixels that got no filter weight
  // in the pass take 0 for the add_sample term and are counted in empty_pixel_passes().
  // Throws std::logic_error if the pass holds splats and splat_scale is 0 (they would be
  // dropped silently).
  void end_pass(double splat_scale = 0.0);

  // Called by end_pass with the pass's Welch sample of every pixel (row-major), before they are
  // added to welch(): checks that need more than per-pixel moments (sums over groups of pixels,
  // validate/render/pixel_groups.h) read the passes here. Empty: no call.
  using PassObserver = std::function<void(const std::vector<Rgb>& pass)>;
  void set_pass_observer(PassObserver observer) { observer_ = std::move(observer); }

  int64_t passes() const { return passes_; }
  int64_t empty_pixel_passes() const { return empty_pixel_passes_; }
  int64_t splats_outside() const { return splats_outside_; }
  const NonFiniteLog& nonfinite() const { return nonfinite_; }

  // Mean of the Welch samples of a pixel (row-major index y * width + x), and the whole image.
  Rgb pixel(int x, int y) const;
  std::vector<Rgb> mean_image() const;
  const WelchImage& welch() const { return welch_; }

 private:
  int width_, height_;
  std::shared_ptr<const Filter> filter_;
  FilmTile pass_;                  // the whole image: sum w L, sum w of the current pass
  std::vector<Rgb> pass_splat_;    // sum of splats of the current pass
  WelchImage welch_;
  int64_t passes_ = 0, empty_pixel_passes_ = 0, splats_outside_ = 0;
  int64_t pass_splats_ = 0;        // splats merged in the current pass
  NonFiniteLog nonfinite_;         // of closed and current passes
  SplatBuffer direct_splats_;      // scratch for splat()
  PassObserver observer_;
  std::vector<Rgb> observed_;      // the pass handed to observer_
};

}  // namespace tb

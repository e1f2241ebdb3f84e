// Per-pass tile sums of a render: the image cut into a gx x gy grid of tiles and, for every pass,
// the sum over each tile's pixels of the pass's Welch samples (RGB). Written by tb render next to
// the EXR (OUT.tiles.json) so that tb compare can test two renders whose pixels are correlated
// within a pass (MCMC: one chain's splats cover the whole image, a PSS pass shares one
// normalisation): passes are independent, so each tile's pass sums are independent samples of the
// tile's estimate, whatever the dependence between pixels and tiles inside a pass
// (validate/pass_tile_compare.h, docs/compare.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"

namespace tb {

class PassTiles {
 public:
  PassTiles() = default;
  // A grid of at most gx x gy tiles (fewer where the image is smaller): tile (i, j) holds the
  // pixels with floor(x gx' / width) = i and floor(y gy' / height) = j.
  PassTiles(int width, int height, int gx = 8, int gy = 8);

  // One closed pass (row-major Welch samples, Film::PassObserver).
  void add_pass(const std::vector<Rgb>& pass);

  int width() const { return width_; }
  int height() const { return height_; }
  int grid_x() const { return gx_; }
  int grid_y() const { return gy_; }
  int tiles() const { return gx_ * gy_; }
  int64_t passes() const { return passes_; }
  // Sum over tile t's pixels in pass p.
  Rgb sum(int64_t pass, int tile) const { return sums_[static_cast<size_t>(pass * tiles() + tile)]; }
  int tile_of(int x, int y) const;

  std::string to_json() const;
  // Throws std::runtime_error naming the file on malformed content.
  static PassTiles read(const std::string& path);

 private:
  int width_ = 0, height_ = 0, gx_ = 0, gy_ = 0;
  int64_t passes_ = 0;
  std::vector<Rgb> sums_;  // pass-major
};

}  // namespace tb

// Comparison of two renders through their per-pass tile sums (lib/film/pass_tiles.h): valid when
// the pixels of a pass are dependent, as they are for every MCMC renderer (one chain's splats
// spread over the image, a PSS pass shares one normalisation) and where the per-pixel and tiled
// Welch tests of validate/image_compare.h, which sum per-pixel variances, underestimate the
// variance of a difference.
//
// The test: passes are independent and identically distributed (each a pure function of the seed
// and its index), so for tile t and channel c the pass sums S_p(t, c) of A and of B are two
// independent samples whose means are the tile's expected sum under each renderer. Welch's t over
// the passes (Satterthwaite dof) gives one p-value per tile-channel, and one per channel for the
// whole-image total. The family p-value is a weighted Bonferroni bound: alpha/2 shared evenly by
// the channel totals and alpha/2 by the tile-channels, p_family = min(2 n_totals min p_total,
// 2 n_tiles min p_tile), capped at 1. Unlike Sidak or Stouffer it needs no independence between
// tiles, which an MCMC pass does not give; the totals get their own half because a wrong
// normalisation, the commonest MCMC failure, scales every tile and shows first in the totals. Tile-channels with zero variance on both sides and equal means are skipped.
// The t approximation asks for tile sums that are roughly normal over passes: few passes of a
// heavy-tailed render (a pixel carried by one chain) can still reject; docs/compare.md gives the
// measured false-alarm rates.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "lib/film/pass_tiles.h"

namespace tb {

struct PassTileCompareResult {
  double alpha = 0.01;
  int64_t passes_a = 0, passes_b = 0;
  int grid_x = 0, grid_y = 0;
  int64_t tested = 0, skipped = 0;  // tile-channel and total statistics
  int64_t tested_tiles = 0, tested_totals = 0;
  double p_min = 1.0, p_family = 1.0;
  // The statistic with the smallest p: tile index (-1: the whole-image total), channel, t, dof,
  // the two means and the relative difference (mean_a - mean_b) / |mean_b| (0 when mean_b = 0).
  int worst_tile = -1, worst_channel = -1;
  double worst_t = 0.0, worst_dof = 0.0, worst_mean_a = 0.0, worst_mean_b = 0.0, worst_rel_diff = 0.0;
  // Whole-image totals per channel: relative difference of the means and its p-value.
  double total_rel_diff[3] = {0, 0, 0}, total_p[3] = {1, 1, 1};
  bool rejects() const { return p_family < alpha; }
  nlohmann::json details() const;
};

// Throws std::invalid_argument when the two files do not describe the same image and grid or a
// side has fewer than 2 passes.
PassTileCompareResult compare_pass_tiles(const PassTiles& a, const PassTiles& b, double alpha);

}  // namespace tb

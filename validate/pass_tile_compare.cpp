#include "validate/pass_tile_compare.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb {
namespace {

struct Stat {
  stats::TestResult t;
  double mean_a = 0, mean_b = 0;
  bool tested = false;
};

template <class A, class B>
Stat welch_over_passes(int64_t na, int64_t nb, A&& a_value, B&& b_value) {
  stats::Welford wa, wb;
  for (int64_t p = 0; p < na; ++p) wa.add(a_value(p));
  for (int64_t p = 0; p < nb; ++p) wb.add(b_value(p));
  Stat s;
  s.mean_a = wa.mean();
  s.mean_b = wb.mean();
  if (wa.variance() == 0.0 && wb.variance() == 0.0) {
    if (s.mean_a == s.mean_b) return s;  // skipped: nothing varies and nothing differs
    s.t = {std::copysign(INFINITY, s.mean_a - s.mean_b), 0.0, 0.0};
    s.tested = true;
    return s;
  }
  s.t = stats::welch_t_test(wa, wb);
  s.tested = true;
  return s;
}

}  // namespace

nlohmann::json PassTileCompareResult::details() const {
  return {{"test", "pass-tile Welch; weighted Bonferroni: alpha/2 over the channel totals, alpha/2 over the tile-channels"},
          {"alpha", alpha},
          {"passes", {passes_a, passes_b}},
          {"grid", {grid_x, grid_y}},
          {"tested", tested},
          {"tested_tiles", tested_tiles},
          {"tested_totals", tested_totals},
          {"skipped", skipped},
          {"p_min", p_min},
          {"p_family", p_family},
          {"rejects", rejects()},
          {"worst", {{"tile", worst_tile}, {"channel", worst_channel}, {"t", worst_t}, {"dof", worst_dof},
                     {"mean_a", worst_mean_a}, {"mean_b", worst_mean_b}, {"rel_diff", worst_rel_diff}}},
          {"total_rel_diff", {total_rel_diff[0], total_rel_diff[1], total_rel_diff[2]}},
          {"total_p", {total_p[0], total_p[1], total_p[2]}}};
}

PassTileCompareResult compare_pass_tiles(const PassTiles& a, const PassTiles& b, double alpha) {
  if (a.width() != b.width() || a.height() != b.height() || a.grid_x() != b.grid_x() || a.grid_y() != b.grid_y())
    throw std::invalid_argument("pass tiles: A and B differ in image size or tile grid");
  if (a.passes() < 2 || b.passes() < 2)
    throw std::invalid_argument("pass tiles: each side needs at least 2 passes (A has " + std::to_string(a.passes()) +
                                ", B " + std::to_string(b.passes()) + ")");
  PassTileCompareResult r;
  r.alpha = alpha;
  r.passes_a = a.passes();
  r.passes_b = b.passes();
  r.grid_x = a.grid_x();
  r.grid_y = a.grid_y();
  std::vector<std::pair<int, double>> tested_p;  // (tile, -1 for a total; p)
  auto consider = [&](const Stat& s, int tile, int c) {
    if (!s.tested) {
      ++r.skipped;
      return;
    }
    ++r.tested;
    tested_p.emplace_back(tile, s.t.p_value);
    if (s.t.p_value < r.p_min || r.worst_channel < 0) {
      r.p_min = std::min(r.p_min, s.t.p_value);
      r.worst_tile = tile;
      r.worst_channel = c;
      r.worst_t = s.t.statistic;
      r.worst_dof = s.t.dof;
      r.worst_mean_a = s.mean_a;
      r.worst_mean_b = s.mean_b;
      r.worst_rel_diff = s.mean_b != 0.0 ? (s.mean_a - s.mean_b) / std::abs(s.mean_b) : 0.0;
    }
  };
  for (int tile = 0; tile < a.tiles(); ++tile)
    for (int c = 0; c < 3; ++c) {
      auto va = [&](int64_t p) { return a.sum(p, tile)[c]; };
      auto vb = [&](int64_t p) { return b.sum(p, tile)[c]; };
      consider(welch_over_passes(a.passes(), b.passes(), va, vb), tile, c);
    }
  for (int c = 0; c < 3; ++c) {
    auto total = [c](const PassTiles& t) {
      return [&t, c](int64_t p) {
        double s = 0.0;
        for (int tile = 0; tile < t.tiles(); ++tile) s += t.sum(p, tile)[c];
        return s;
      };
    };
    auto ta = total(a);
    auto tb_ = total(b);
    const Stat s = welch_over_passes(a.passes(), b.passes(), ta, tb_);
    r.total_p[c] = s.tested ? s.t.p_value : 1.0;
    r.total_rel_diff[c] = s.mean_b != 0.0 ? (s.mean_a - s.mean_b) / std::abs(s.mean_b) : 0.0;
    consider(s, -1, c);
  }
  // Weighted Bonferroni: half of alpha for the (at most 3) channel totals, half for the tiles, each
  // half split evenly; valid under any dependence. The totals carry the most common MCMC failure (a
  // wrong normalisation scales every pixel) and would drown among 195 equal shares.
  double p_tiles = 1.0, p_totals = 1.0;
  int64_t n_tiles = 0, n_totals = 0;
  for (const auto& [tile, p] : tested_p) {
    if (tile < 0) {
      ++n_totals;
      p_totals = std::min(p_totals, p);
    } else {
      ++n_tiles;
      p_tiles = std::min(p_tiles, p);
    }
  }
  const double share_tiles = n_totals > 0 ? 2.0 : 1.0, share_totals = n_tiles > 0 ? 2.0 : 1.0;
  r.p_family = std::min({1.0, n_tiles > 0 ? share_tiles * static_cast<double>(n_tiles) * p_tiles : 1.0,
                         n_totals > 0 ? share_totals * static_cast<double>(n_totals) * p_totals : 1.0});
  r.tested_tiles = n_tiles;
  r.tested_totals = n_totals;
  return r;
}

}  // namespace tb

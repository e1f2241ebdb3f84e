// A product grid of bins for the stationarity checks: per dimension `res` equal cells over
// [lo, hi] plus one tail cell on each side, so every state falls in a bin. Cell edges are given
// to a target, which integrates its density over each cell exactly.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "lib/core/math.h"

namespace tb::mcmc {

template <size_t N>
class GridBins {
 public:
  GridBins() = default;
  GridBins(std::array<double, N> lo, std::array<double, N> hi, int res) : res_(res) {
    for (size_t d = 0; d < N; ++d) {
      edges_[d].push_back(-kInfinity);
      for (int i = 0; i <= res; ++i) edges_[d].push_back(lo[d] + (hi[d] - lo[d]) * i / res);
      edges_[d].push_back(kInfinity);
    }
  }
  int cells_per_dim() const { return res_ + 2; }
  int count() const {
    int c = 1;
    for (size_t d = 0; d < N; ++d) c *= cells_per_dim();
    return c;
  }
  int index(const std::array<double, N>& x) const {
    int idx = 0;
    for (size_t d = N; d-- > 0;) {
      const auto& e = edges_[d];
      const int c = static_cast<int>(std::upper_bound(e.begin() + 1, e.end() - 1, x[d]) - e.begin()) - 1;
      idx = idx * cells_per_dim() + c;
    }
    return idx;
  }
  // Cell coordinates of a flat index.
  std::array<int, N> cell(int idx) const {
    std::array<int, N> c{};
    for (size_t d = 0; d < N; ++d) {
      c[d] = idx % cells_per_dim();
      idx /= cells_per_dim();
    }
    return c;
  }
  double lower(size_t d, int c) const { return edges_[d][c]; }
  double upper(size_t d, int c) const { return edges_[d][c + 1]; }

 private:
  int res_ = 0;
  std::array<std::vector<double>, N> edges_;
};

}  // namespace tb::mcmc

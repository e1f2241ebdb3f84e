#include "lib/core/discrete.h"

#include <algorithm>
#include <cmath>

#include "lib/core/math.h"

namespace tb {
namespace {
// Normalised weights, or empty when they cannot define a distribution.
std::optional<std::vector<double>> normalise(std::span<const double> w) {
  if (w.empty() || w.size() > (size_t{1} << 31)) return std::nullopt;
  CompensatedSum sum;
  for (double x : w) {
    if (!(x >= 0) || !std::isfinite(x)) return std::nullopt;
    sum += x;
  }
  const double total = sum.value();
  if (!(total > 0) || !std::isfinite(total)) return std::nullopt;
  std::vector<double> p(w.size());
  for (size_t i = 0; i < w.size(); ++i) p[i] = w[i] / total;
  return p;
}
}  // namespace

std::optional<AliasTable> AliasTable::create(std::span<const double> weights) {
  auto p = normalise(weights);
  if (!p) return std::nullopt;
  AliasTable t;
  t.pmf_ = std::move(*p);
  const size_t n = t.pmf_.size();
  t.bins_.resize(n);
  // Vose's algorithm: scaled probabilities n p_i; pair each "small" (< 1) bin with a
  // "large" one that donates the remainder.
  std::vector<double> scaled(n);
  std::vector<uint32_t> small, large;
  for (size_t i = 0; i < n; ++i) {
    scaled[i] = t.pmf_[i] * static_cast<double>(n);
    (scaled[i] < 1.0 ? small : large).push_back(static_cast<uint32_t>(i));
  }
  while (!small.empty() && !large.empty()) {
    const uint32_t s = small.back(), l = large.back();
    small.pop_back();
    large.pop_back();
    t.bins_[s] = {scaled[s], l};
    scaled[l] = (scaled[l] + scaled[s]) - 1.0;
    (scaled[l] < 1.0 ? small : large).push_back(l);
  }
  // Leftovers are 1 up to round-off. A leftover of zero weight (possible only through
  // round-off) must still never be chosen: it keeps q = 0 and an alias of positive weight.
  const uint32_t any_positive =
      static_cast<uint32_t>(std::find_if(t.pmf_.begin(), t.pmf_.end(), [](double x) { return x > 0; }) - t.pmf_.begin());
  for (auto* list : {&small, &large})
    for (uint32_t i : *list) t.bins_[i] = t.pmf_[i] > 0 ? Bin{1.0, i} : Bin{0.0, any_positive};
  return t;
}

DiscreteSample AliasTable::sample(double u) const {
  const double n = static_cast<double>(bins_.size());
  const double scaled = u * n;
  const size_t i = std::min(static_cast<size_t>(scaled), bins_.size() - 1);
  const double frac = std::min(scaled - static_cast<double>(i), kOneMinusEpsilon);
  const Bin& b = bins_[i];
  if (frac < b.q) return {i, std::min(frac / b.q, kOneMinusEpsilon)};
  return {b.alias, std::min((frac - b.q) / (1.0 - b.q), kOneMinusEpsilon)};
}

std::optional<DiscreteCdf> DiscreteCdf::create(std::span<const double> weights) {
  auto p = normalise(weights);
  if (!p) return std::nullopt;
  DiscreteCdf d;
  const size_t n = p->size();
  d.cdf_.resize(n + 1);
  CompensatedSum acc;
  d.cdf_[0] = 0;
  size_t last_positive = 0;
  for (size_t i = 0; i < n; ++i) {
    acc += (*p)[i];
    d.cdf_[i + 1] = acc.value();
    if ((*p)[i] > 0) last_positive = i;
  }
  // Exactly 1 from the last positive weight on, so trailing zero weights have zero width.
  for (size_t i = last_positive + 1; i <= n; ++i) d.cdf_[i] = 1.0;
  return d;
}

DiscreteSample DiscreteCdf::sample(double u) const {
  // First k with cdf_[k] > u; the index k - 1 has cdf_[k-1] <= u < cdf_[k], so a positive width.
  const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u);
  const size_t i = std::min(static_cast<size_t>(it - cdf_.begin()) - 1, size() - 1);
  const double w = cdf_[i + 1] - cdf_[i];
  return {i, std::clamp((u - cdf_[i]) / w, 0.0, kOneMinusEpsilon)};
}

double DiscreteCdf::invert(size_t index, double u_remapped) const {
  return std::min(cdf_[index] + u_remapped * (cdf_[index + 1] - cdf_[index]), kOneMinusEpsilon);
}

}  // namespace tb

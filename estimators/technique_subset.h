// A random subset of techniques (West et al. 2022, Sec. 3.1: "we are free to choose a (random)
// subset"): k of the techniques are chosen uniformly without replacement, independently of the
// samples, plus every technique marked `always` (e.g. the defensive one, so that the coverage
// condition holds for every subset). Conditioned on the subset MMIS is unbiased, so it is unbiased
// overall. The result is a count vector with 0 for the techniques left out.
#pragma once

#include <numeric>
#include <span>
#include <stdexcept>
#include <vector>

#include "lib/core/uniforms.h"

namespace tb {

inline std::vector<int> random_subset_counts(std::span<const int> counts, std::span<const bool> always, int k,
                                             Uniforms& u) {
  if (always.size() != counts.size()) throw std::invalid_argument("random_subset_counts: one flag per technique");
  std::vector<size_t> pool;
  std::vector<int> out(counts.size(), 0);
  for (size_t i = 0; i < counts.size(); ++i) {
    if (always[i])
      out[i] = counts[i];
    else
      pool.push_back(i);
  }
  // Partial Fisher-Yates shuffle driven by uniforms: one uniform per chosen technique.
  const size_t take = std::min(pool.size(), static_cast<size_t>(std::max(k, 0)));
  for (size_t s = 0; s < take; ++s) {
    const size_t r = s + std::min(pool.size() - s - 1, static_cast<size_t>(u.next() * static_cast<double>(pool.size() - s)));
    std::swap(pool[s], pool[r]);
    out[pool[s]] = counts[pool[s]];
  }
  return out;
}

}  // namespace tb

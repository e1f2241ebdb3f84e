// MMIS_n at a fixed sample budget (West et al. 2022, Sec. 3.2): n technique-sample pairs from each of
// the T marginal techniques per realisation, N / (nT) independent realisations averaged. The total
// cost is n·N·T conditional pdf evaluations, linear in n; the reference MIS costs N·T.
#pragma once

#include <span>
#include <stdexcept>
#include <vector>

#include "estimators/mmis.h"

namespace tb {

template <MarginalTechnique M, Integrand<typename M::Sample> F>
Estimate estimate_mmis_budget(const F& f, std::span<const M> techniques, int n, int budget, Uniforms& u) {
  const int t = static_cast<int>(techniques.size());
  if (n <= 0 || budget % (n * t) != 0)
    throw std::invalid_argument("estimate_mmis_budget: the budget N must be a multiple of n·T");
  const int realisations = budget / (n * t);
  const std::vector<int> counts(techniques.size(), n);
  using NC = NoClassical<typename M::Sample>;
  // One draw refilled by every realisation: after the first, no realisation allocates.
  MmisDraw<typename M::Sample, typename M::Aux> d;
  d.aux.reserve(static_cast<size_t>(n) * techniques.size());
  d.xs.reserve(static_cast<size_t>(n) * techniques.size());
  Estimate total;
  for (int k = 0; k < realisations; ++k) {
    draw_mmis_into(d, std::span<const NC>{}, std::span<const int>{}, techniques, std::span<const int>(counts), u);
    total += evaluate_mmis(f, std::span<const NC>{}, std::span<const int>{}, techniques, d);  // West et al. 2022, Eq. 6
  }
  total.value /= realisations;
  return total;
}

}  // namespace tb

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
  Estimate total;
  for (int k = 0; k < realisations; ++k) total += estimate_mmis(f, techniques, std::span<const int>(counts), u);
  total.value /= realisations;
  return total;
}

}  // namespace tb

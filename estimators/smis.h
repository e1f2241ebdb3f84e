// Stochastic MIS over one technique space (West et al. 2020, the SMIS estimator with the balance
// heuristic): draw n technique-sample pairs (t_j, x_j), t_j ~ p(t), x_j ~ p(x | t_j), and
//   <I> = Σ_j f(x_j) / Σ_j' p(x_j | t_j').
// Unbiased when, for every x with f(x) ≠ 0, some sampled conditional technique has p(x | t) > 0 (for
// almost every draw of the t's). Cost: n² conditional pdf evaluations. West et al. 2022 note that
// MMIS (mmis.h) with T = 1 reduces to this; the tests check the identity.
#pragma once

#include <optional>
#include <vector>

#include "estimators/concepts.h"
#include "estimators/estimate.h"

namespace tb {

template <MarginalTechnique M, Integrand<typename M::Sample> F>
Estimate estimate_smis(const F& f, const M& technique, int n, Uniforms& u) {
  std::vector<typename M::Aux> aux;
  std::vector<std::optional<typename M::Sample>> xs;
  aux.reserve(n);
  xs.reserve(n);
  Estimate e;
  for (int j = 0; j < n; ++j) {
    ++e.samples;
    auto t = technique.sample_aux(u);
    if (!t) {  // a failed t is a conditional technique of zero probability: it drops out everywhere
      ++e.failed;
      continue;
    }
    auto x = technique.sample(*t, u);
    if (!x) ++e.failed;
    aux.push_back(*t);
    xs.push_back(std::move(x));
  }
  for (const auto& x : xs) {
    if (!x) continue;
    double d = 0.0;
    for (const auto& t : aux) d += technique.pdf(*x, t);
    e.pdf_evals += static_cast<int64_t>(aux.size());
    e.add(safe_ratio(static_cast<double>(f(*x)), d));
  }
  return e;
}

}  // namespace tb

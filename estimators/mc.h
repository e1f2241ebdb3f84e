// Plain Monte Carlo: <I> = (1/N) Σ f(x_j) / p(x_j), x_j ~ p (Veach 1997, Eq. 2.2). Unbiased where
// p > 0 wherever f ≠ 0.
#pragma once

#include "estimators/concepts.h"
#include "estimators/estimate.h"

namespace tb {

template <Technique T, Integrand<typename T::Sample> F>
Estimate estimate_mc(const F& f, const T& technique, int64_t n, Uniforms& u) {
  Estimate e;
  const double inv_n = 1.0 / static_cast<double>(n);
  for (int64_t j = 0; j < n; ++j) {
    ++e.samples;
    const auto x = technique.sample(u);
    if (!x) {
      ++e.failed;
      continue;
    }
    const double p = technique.pdf(*x);
    ++e.pdf_evals;
    e.add(safe_ratio(static_cast<double>(f(*x)), p) * inv_n);
  }
  return e;
}

}  // namespace tb

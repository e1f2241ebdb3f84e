// Continuous multiple importance sampling (CMIS, West et al. 2020) over one technique space: a
// continuum of conditional techniques p(x | t), t in a technique space T, each technique chosen with
// the density p(t). n technique-sample pairs (t_j, x_j), t_j ~ p(t), x_j ~ p(x | t_j), and
//   <I> = (1/n) Σ_j w(t_j, x_j) f(x_j) / (p(t_j) p(x_j | t_j)),
// unbiased when the weights are normalised over the technique space, ∫_T w(t, x) dt = 1 for every
// x with f(x) ≠ 0 (the continuous form of the condition Σ_i w_i(x) = 1 on discrete MIS weights,
// Veach 1997, Sec. 9.2).
// The continuous balance heuristic is w(t, x) = p(t) p(x | t) / p(x) with the marginal
// p(x) = ∫_T p(t') p(x | t') dt' (West et al. 2022, Eq. 2), so that <I> = (1/n) Σ_j f(x_j) / p(x_j):
// importance sampling from the marginal. Stochastic MIS (smis.h) is this estimator with p(x)
// replaced by (1/n) Σ_j' p(x | t_j') over the sampled t's (x_j's own among them), which keeps it
// unbiased; MMIS (mmis.h) does the same over several technique spaces. CMIS therefore needs a technique whose
// marginal can be evaluated (ContinuousTechnique), which is what makes it a reference, not a
// practical estimator, when the marginal is an integral over paths.
// Cost: one p(x | t) and one p(x) per sample for the balance heuristic.
#pragma once

#include <cstdint>

#include "estimators/concepts.h"
#include "estimators/estimate.h"

namespace tb {

// A marginal technique whose selection density p(t) and marginal p(x) = ∫ p(t) p(x | t) dt can be
// evaluated (the latter in closed form or by quadrature). Same measures as MarginalTechnique.
template <class T>
concept ContinuousTechnique = MarginalTechnique<T> &&
                              requires(const T& m, const typename T::Aux& a, const typename T::Sample& x) {
                                { m.aux_pdf(a) } -> std::convertible_to<double>;
                                { m.marginal_pdf(x) } -> std::convertible_to<double>;
                              };

// A CMIS weighting function w(t, x), given the joint density q = p(t) p(x | t) already evaluated at
// the sample; pdf_evals is how many density evaluations (p(x | t) or p(x)) it makes per call.
template <class W, class M>
concept ContinuousMisWeight =
    requires(const W& w, const M& m, const typename M::Sample& x, const typename M::Aux& a, double q) {
      { w.weight(m, x, a, q) } -> std::convertible_to<double>;
      { W::pdf_evals } -> std::convertible_to<int64_t>;
    };

// w(t, x) = p(t) p(x | t) / p(x) (West et al. 2020, the continuous balance heuristic): ∫_T w dt = 1.
struct ContinuousBalanceHeuristic {
  static constexpr int64_t pdf_evals = 1;
  template <ContinuousTechnique M>
  double weight(const M& m, const typename M::Sample& x, const typename M::Aux&, double q) const {
    return safe_ratio(q, static_cast<double>(m.marginal_pdf(x)));
  }
};

template <ContinuousTechnique M, Integrand<typename M::Sample> F, class W = ContinuousBalanceHeuristic>
  requires ContinuousMisWeight<W, M>
Estimate estimate_cmis(const F& f, const M& technique, int n, Uniforms& u, const W& weight = {}) {
  Estimate e;
  const double inv_n = 1.0 / static_cast<double>(n);
  for (int j = 0; j < n; ++j) {
    ++e.samples;
    const auto t = technique.sample_aux(u);
    if (!t) {
      ++e.failed;
      continue;
    }
    const auto x = technique.sample(*t, u);
    if (!x) {
      ++e.failed;
      continue;
    }
    const double q = static_cast<double>(technique.aux_pdf(*t)) * static_cast<double>(technique.pdf(*x, *t));
    const double fx = f(*x);
    e.pdf_evals += 1 + W::pdf_evals;
    if (fx == 0.0) continue;
    // w f / (p(t) p(x | t)): the CMIS estimator above.
    e.add(safe_ratio(weight.weight(technique, *x, *t, q) * fx, q) * inv_n);
  }
  return e;
}

}  // namespace tb

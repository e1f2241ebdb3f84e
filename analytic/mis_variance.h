// Exact variances of classical estimators of ∫_0^1 f by quadrature (docs/validation.md B: the reference
// MIS variance). For multi-sample MIS with the balance heuristic and n_i samples from p_i
// (Veach 1997, Eq. 9.4 with w_i = n_i p_i / P, P = Σ_k n_k p_k):
//   F = Σ_i Σ_j f(x_ij) / P(x_ij),   Var F = Σ_i n_i ( ∫ f² p_i / P² dx − (∫ f p_i / P dx)² ).
// Plain MC is the case of one technique. The densities may themselves be computed by quadrature
// (exact marginals of marginal techniques); their values are cached per x.
#pragma once

#include <functional>
#include <vector>

namespace tb {

struct MisVarianceInput {
  std::function<double(double)> f;            // integrand on [0, 1]
  std::vector<std::function<double(double)>> pdfs;  // p_i(x), Lebesgue measure
  std::vector<int> counts;                    // n_i
  std::vector<double> breakpoints;            // discontinuities of f and of the p_i in (0, 1)
};

// Variance of one realisation of the balance-heuristic multi-sample MIS estimator. +inf when f ≠ 0
// somewhere no technique samples (the estimator would be biased there).
double mis_balance_variance(const MisVarianceInput& in);

}  // namespace tb

// Multiple importance sampling over classical techniques (Veach 1997, Ch. 9).
// Multi-sample (Veach Eq. 9.4, West et al. 2022 Eq. 1):
//   <I> = Σ_i (1/n_i) Σ_j w_i(x_ij) f(x_ij) / p_i(x_ij),  q_k = n_k p_k(x),
// One-sample (Veach Sec. 9.2.4): technique I ~ c, x ~ p_I,  <I> = w_I(x) f(x) / (c_I p_I(x)),  q_k = c_k p_k(x).
// Every technique's pdf is evaluated at every sample: cost Σ n_i · T pdf evaluations.
#pragma once

#include <span>
#include <stdexcept>
#include <vector>

#include "estimators/concepts.h"
#include "estimators/estimate.h"
#include "estimators/mis_heuristics.h"

namespace tb {

// counts[i] = n_i samples from techniques[i] (n_i = 0 leaves the technique out).
template <Technique T, Integrand<typename T::Sample> F, MisHeuristic H = BalanceHeuristic>
Estimate estimate_mis(const F& f, std::span<const T> techniques, std::span<const int> counts, Uniforms& u,
                      const H& heuristic = {}) {
  if (techniques.size() != counts.size()) throw std::invalid_argument("estimate_mis: one count per technique");
  const size_t nt = techniques.size();
  std::vector<double> q(nt);
  Estimate e;
  for (size_t i = 0; i < nt; ++i) {
    for (int j = 0; j < counts[i]; ++j) {
      ++e.samples;
      const auto x = techniques[i].sample(u);
      if (!x) {
        ++e.failed;
        continue;
      }
      for (size_t k = 0; k < nt; ++k) q[k] = counts[k] > 0 ? counts[k] * static_cast<double>(techniques[k].pdf(*x)) : 0.0;
      e.pdf_evals += static_cast<int64_t>(nt);
      const double fx = f(*x);
      if (fx == 0.0) continue;
      const double w = heuristic.weight(q, i);
      // w_i f / (n_i p_i) = w_i f / q_i.
      e.add(w == 0.0 ? 0.0 : w * fx / q[i]);
    }
  }
  return e;
}

// probabilities[i] = c_i, the probability of choosing technique i (they must sum to one). One
// uniform picks the technique; the rest go to the technique's sampler.
template <Technique T, Integrand<typename T::Sample> F, MisHeuristic H = BalanceHeuristic>
Estimate estimate_one_sample_mis(const F& f, std::span<const T> techniques, std::span<const double> probabilities,
                                 Uniforms& u, const H& heuristic = {}) {
  if (techniques.size() != probabilities.size()) throw std::invalid_argument("one-sample MIS: one c_i per technique");
  const size_t nt = techniques.size();
  double r = u.next();
  size_t chosen = nt - 1;
  for (size_t i = 0; i < nt; ++i) {
    if (r < probabilities[i]) {
      chosen = i;
      break;
    }
    r -= probabilities[i];
  }
  while (probabilities[chosen] <= 0.0) --chosen;  // round-off pushed r past the last positive c_i
  Estimate e;
  ++e.samples;
  const auto x = techniques[chosen].sample(u);
  if (!x) {
    ++e.failed;
    return e;
  }
  std::vector<double> q(nt);
  for (size_t k = 0; k < nt; ++k) q[k] = probabilities[k] * static_cast<double>(techniques[k].pdf(*x));
  e.pdf_evals += static_cast<int64_t>(nt);
  const double fx = f(*x);
  if (fx == 0.0) return e;
  const double w = heuristic.weight(q, chosen);
  e.add(w == 0.0 ? 0.0 : w * fx / q[chosen]);
  return e;
}

}  // namespace tb

// Marginal multiple importance sampling (West et al. 2022, Eq. 6), with classical techniques mixed in
// by splitting the balance-heuristic denominator into a classical and a marginal sum (Sec. 3.1):
//   <I> = Σ_{samples x} f(x) / [ Σ_c n_c p_c(x) + Σ_m Σ_{j'} p_m(x | t_{m,j'}) ],
// where n_c samples come from classical technique c and n_m technique-sample pairs (t, x) from
// marginal technique m. Classical techniques can also be extruded into marginal ones
// (extruded_technique.h): the two forms agree exactly in expectation and to round-off per draw.
// Unbiased as long as for every x with f(x) ≠ 0 some classical technique or sampled conditional
// technique has positive density (West et al. 2022, below Eq. 6). A count of 0 leaves a technique
// out, which is how a random subset of techniques is used (technique_subset.h).
// Cost: S·(C + P) pdf evaluations for S samples, C classical techniques in use and P sampled
// auxiliaries: with n pairs from each of T marginal techniques, (nT)² per realisation.
#pragma once

#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "estimators/concepts.h"
#include "estimators/estimate.h"

namespace tb {

// A marginal technique with the number of technique-sample pairs n_i drawn from it.
template <class M>
struct MarginalGroup {
  std::span<const M> techniques;
  std::span<const int> counts;
};

// The technique-sample pairs of one MMIS realisation: classical samples first, then the
// marginal (t, x) pairs. Drawing them and evaluating Eq. 6 over them are separate steps so that
// the evaluation (n·N·T conditional pdf evaluations) can be timed on its own.
template <class X, class Aux>
struct MmisDraw {
  struct Pair {
    size_t technique;
    Aux t;
  };
  std::vector<Pair> aux;
  std::vector<std::optional<X>> xs;
  int64_t samples = 0, failed = 0;
};

template <Technique C, MarginalTechnique M>
  requires std::same_as<typename C::Sample, typename M::Sample>
MmisDraw<typename M::Sample, typename M::Aux> draw_mmis(std::span<const C> classical,
                                                       std::span<const int> classical_counts,
                                                       std::span<const M> marginal,
                                                       std::span<const int> marginal_counts, Uniforms& u) {
  if (classical.size() != classical_counts.size() || marginal.size() != marginal_counts.size())
    throw std::invalid_argument("estimate_mmis: one count per technique");
  MmisDraw<typename M::Sample, typename M::Aux> d;
  // The order of uniforms is part of the estimator's definition (fixed so runs are reproducible).
  for (size_t c = 0; c < classical.size(); ++c)
    for (int j = 0; j < classical_counts[c]; ++j) {
      ++d.samples;
      auto x = classical[c].sample(u);
      if (!x) ++d.failed;
      d.xs.push_back(std::move(x));
    }
  for (size_t m = 0; m < marginal.size(); ++m)
    for (int j = 0; j < marginal_counts[m]; ++j) {
      ++d.samples;
      auto t = marginal[m].sample_aux(u);
      if (!t) {
        ++d.failed;
        continue;
      }
      auto x = marginal[m].sample(*t, u);
      if (!x) ++d.failed;
      d.aux.push_back({m, *t});
      d.xs.push_back(std::move(x));
    }
  return d;
}

// Eq. 6 (West et al. 2022) over drawn pairs: sum over samples of f(x) / (sum_c n_c p_c(x) +
// sum_(i,j) p_i(x | t_ij)).
template <Technique C, MarginalTechnique M, Integrand<typename M::Sample> F>
  requires std::same_as<typename C::Sample, typename M::Sample>
Estimate evaluate_mmis(const F& f, std::span<const C> classical, std::span<const int> classical_counts,
                       std::span<const M> marginal, const MmisDraw<typename M::Sample, typename M::Aux>& d) {
  Estimate e;
  e.samples = d.samples;
  e.failed = d.failed;
  for (const auto& x : d.xs) {
    if (!x) continue;
    double den = 0.0;
    for (size_t c = 0; c < classical.size(); ++c)
      if (classical_counts[c] > 0) {
        den += classical_counts[c] * static_cast<double>(classical[c].pdf(*x));
        ++e.pdf_evals;
      }
    for (const auto& a : d.aux) den += marginal[a.technique].pdf(*x, a.t);  // West et al. 2022, Eq. 6 denominator
    e.pdf_evals += static_cast<int64_t>(d.aux.size());
    e.add(safe_ratio(static_cast<double>(f(*x)), den));
  }
  return e;
}

template <Technique C, MarginalTechnique M, Integrand<typename M::Sample> F>
  requires std::same_as<typename C::Sample, typename M::Sample>
Estimate estimate_mmis(const F& f, std::span<const C> classical, std::span<const int> classical_counts,
                       std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  const auto d = draw_mmis(classical, classical_counts, marginal, marginal_counts, u);
  return evaluate_mmis(f, classical, classical_counts, marginal, d);
}

// A classical technique that is never sampled: lets the all-marginal form reuse the general one.
template <class X>
struct NoClassical {
  using Sample = X;
  std::optional<Sample> sample(Uniforms&) const { return std::nullopt; }
  double pdf(const Sample&) const { return 0.0; }
};

// All techniques marginal (classical ones extruded): Eq. 6 as printed.
template <MarginalTechnique M, Integrand<typename M::Sample> F>
Estimate estimate_mmis(const F& f, std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  return estimate_mmis(f, std::span<const NoClassical<typename M::Sample>>{}, std::span<const int>{}, marginal,
                       marginal_counts, u);
}

}  // namespace tb

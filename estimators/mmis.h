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

template <Technique C, MarginalTechnique M, Integrand<typename M::Sample> F>
  requires std::same_as<typename C::Sample, typename M::Sample>
Estimate estimate_mmis(const F& f, std::span<const C> classical, std::span<const int> classical_counts,
                       std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  using X = typename M::Sample;
  if (classical.size() != classical_counts.size() || marginal.size() != marginal_counts.size())
    throw std::invalid_argument("estimate_mmis: one count per technique");
  struct Aux {
    size_t technique;
    typename M::Aux t;
  };
  std::vector<Aux> aux;
  std::vector<std::optional<X>> xs;
  Estimate e;
  // Classical samples first, then the marginal pairs: the order of uniforms is part of the estimator's
  // definition (fixed so that runs are reproducible).
  for (size_t c = 0; c < classical.size(); ++c)
    for (int j = 0; j < classical_counts[c]; ++j) {
      ++e.samples;
      auto x = classical[c].sample(u);
      if (!x) ++e.failed;
      xs.push_back(std::move(x));
    }
  for (size_t m = 0; m < marginal.size(); ++m)
    for (int j = 0; j < marginal_counts[m]; ++j) {
      ++e.samples;
      auto t = marginal[m].sample_aux(u);
      if (!t) {
        ++e.failed;
        continue;
      }
      auto x = marginal[m].sample(*t, u);
      if (!x) ++e.failed;
      aux.push_back({m, *t});
      xs.push_back(std::move(x));
    }
  for (const auto& x : xs) {
    if (!x) continue;
    double d = 0.0;
    for (size_t c = 0; c < classical.size(); ++c)
      if (classical_counts[c] > 0) {
        d += classical_counts[c] * static_cast<double>(classical[c].pdf(*x));
        ++e.pdf_evals;
      }
    for (const Aux& a : aux) d += marginal[a.technique].pdf(*x, a.t);  // West et al. 2022, Eq. 6 denominator
    e.pdf_evals += static_cast<int64_t>(aux.size());
    e.add(safe_ratio(static_cast<double>(f(*x)), d));
  }
  return e;
}

// All techniques marginal (classical ones extruded): Eq. 6 as printed.
template <MarginalTechnique M, Integrand<typename M::Sample> F>
Estimate estimate_mmis(const F& f, std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  struct NoClassical {
    using Sample = typename M::Sample;
    std::optional<Sample> sample(Uniforms&) const { return std::nullopt; }
    double pdf(const Sample&) const { return 0.0; }
  };
  return estimate_mmis(f, std::span<const NoClassical>{}, std::span<const int>{}, marginal, marginal_counts, u);
}

}  // namespace tb

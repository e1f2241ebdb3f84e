// Flux symmetry (docs/validation.md E, third item). Chains start from exact draws of pi and run `steps`
// transitions; every transition between different bins i -> j is counted. For a kernel reversible
// with respect to pi, the chain is stationary from its first step and E[N_ij] = E[N_ji]. Two tests,
// each at alpha/2 (Šidák over the two, family-wise alpha):
//  - per bin pair with N_ij + N_ji >= min_count: exact binomial test of N_ij against N_ij + N_ji at
//    p = 1/2, the smallest p-value Šidák-adjusted over the pairs tested (finds one bad pair);
//  - globally, sum over the same pairs of (N_ij - N_ji)^2 / (N_ij + N_ji) against chi-square with
//    one dof per pair (finds a small asymmetry spread over many pairs).
// Transitions inside one chain are dependent; for reversible chains back-and-forth moves make
// N_ij - N_ji less variable than binomial, so the test errs on the conservative side.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/mcmc/checker_concepts.h"
#include "validate/stats/tests.h"

namespace tb::mcmc {

struct FluxSymmetryResult {
  int64_t chains = 0, steps = 0, transitions = 0, accepted = 0;
  int64_t pairs_tested = 0;
  double min_pair_p = 1.0, sidak_p = 1.0;  // smallest binomial p and its Šidák adjustment
  int worst_i = -1, worst_j = -1;
  int64_t worst_nij = 0, worst_nji = 0;
  double chi2 = 0.0, chi2_p = 1.0;
  double alpha = 0.0;
  bool passed = false;
  std::string message;
};

template <MoveKernel K, ExactTarget Tg>
FluxSymmetryResult check_flux_symmetry(const K& kernel, const Tg& target, int64_t chains, int64_t steps, uint64_t seed,
                                       uint64_t key, double alpha, int64_t min_count = 20) {
  const int nb = target.bin_count();
  constexpr int64_t kChunk = 32;
  const int64_t chunks = (chains + kChunk - 1) / kChunk;
  std::vector<std::vector<int64_t>> counts(chunks);
  std::vector<int64_t> acc(chunks, 0);
  parallel_for(static_cast<size_t>(chunks), [&](size_t c) {
    auto& n = counts[c];
    n.assign(static_cast<size_t>(nb) * nb, 0);
    const int64_t end = std::min<int64_t>(chains, (static_cast<int64_t>(c) + 1) * kChunk);
    for (int64_t ch = static_cast<int64_t>(c) * kChunk; ch < end; ++ch) {
      Rng rng = Rng::for_sample(seed, key, ch);
      RngUniforms u(rng);
      typename K::State x = target.sample_exact(u);
      int bx = target.bin_of(x);
      for (int64_t s = 0; s < steps; ++s) {
        auto t = step(kernel, x, u);
        if (!t.accepted) continue;
        ++acc[c];
        x = *t.proposed;
        const int by = target.bin_of(x);
        if (by != bx) ++n[static_cast<size_t>(bx) * nb + by];
        bx = by;
      }
    }
  });
  std::vector<int64_t> n(static_cast<size_t>(nb) * nb, 0);
  FluxSymmetryResult r;
  for (int64_t c = 0; c < chunks; ++c) {
    for (size_t i = 0; i < n.size(); ++i) n[i] += counts[c][i];
    r.accepted += acc[c];
  }
  r.chains = chains;
  r.steps = steps;
  r.transitions = chains * steps;
  r.alpha = alpha;
  for (int i = 0; i < nb; ++i)
    for (int j = i + 1; j < nb; ++j) {
      const int64_t a = n[static_cast<size_t>(i) * nb + j], b = n[static_cast<size_t>(j) * nb + i];
      if (a + b < min_count) continue;
      ++r.pairs_tested;
      const double p = stats::binomial_test(a, a + b, 0.5).p_value;
      r.chi2 += static_cast<double>((a - b) * (a - b)) / static_cast<double>(a + b);
      if (p < r.min_pair_p) {
        r.min_pair_p = p;
        r.worst_i = i;
        r.worst_j = j;
        r.worst_nij = a;
        r.worst_nji = b;
      }
    }
  if (r.pairs_tested > 0) {
    r.sidak_p = stats::sidak_adjust(r.min_pair_p, r.pairs_tested);
    r.chi2_p = stats::chi_squared_sf(r.chi2, static_cast<double>(r.pairs_tested));
  }
  const double a2 = stats::sidak_alpha(alpha, 2);
  r.passed = r.pairs_tested > 0 && r.sidak_p >= a2 && r.chi2_p >= a2;
  r.message = fmt::format("{} chains x {} steps, {} bin pairs tested: worst pair ({}, {}) N = {} vs {}, Šidák p = "
                          "{:.3g}; global chi2 = {:.1f} on {} dof, p = {:.3g} (each at {:.2g})",
                          chains, steps, r.pairs_tested, r.worst_i, r.worst_j, r.worst_nij, r.worst_nji, r.sidak_p,
                          r.chi2, r.pairs_tested, r.chi2_p, a2);
  return r;
}

}  // namespace tb::mcmc

// Diagnostics reported for every chain run (docs/validation.md E, "Diagnostics, not proofs"): m chains
// started from exact draws, the target's scalar summary recorded at every step, split R-hat
// (rank-normalised, Vehtari et al. 2021) and the multi-chain effective sample size, from
// validate/stats/mcmc_diagnostics.h; plus the mean acceptance probability.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/mcmc/checker_concepts.h"
#include "validate/stats/mcmc_diagnostics.h"

namespace tb::mcmc {

struct ChainDiagnostics {
  int64_t chains = 0, length = 0;
  double split_rhat = 0.0, rank_rhat = 0.0, ess = 0.0, mean_acceptance = 0.0;
  std::string message;
  nlohmann::json json() const {
    return {{"chains", chains}, {"length", length}, {"split_rhat", split_rhat}, {"rank_normalized_split_rhat", rank_rhat},
            {"ess", ess}, {"mean_acceptance", mean_acceptance}};
  }
};

template <MoveKernel K, ExactTarget Tg>
ChainDiagnostics chain_diagnostics(const K& kernel, const Tg& target, int chains, int64_t length, uint64_t seed,
                                   uint64_t key) {
  std::vector<std::vector<double>> f(chains, std::vector<double>(length));
  std::vector<double> acc(chains, 0.0);
  parallel_for(static_cast<size_t>(chains), [&](size_t c) {
    Rng rng = Rng::for_sample(seed, key, c);
    RngUniforms u(rng);
    typename K::State x = target.sample_exact(u);
    for (int64_t t = 0; t < length; ++t) {
      const auto tr = step(kernel, x, u);
      acc[c] += tr.acceptance;
      x = tr.next();
      f[c][t] = target.summary(x);
    }
  });
  ChainDiagnostics d;
  d.chains = chains;
  d.length = length;
  d.split_rhat = stats::split_rhat(f);
  d.rank_rhat = stats::rank_normalized_split_rhat(f);
  d.ess = stats::multichain_ess(f);
  for (double a : acc) d.mean_acceptance += a / static_cast<double>(chains * length);
  d.message = fmt::format("split R-hat {:.4f} (rank-normalised {:.4f}), ESS {:.0f} of {} draws, mean acceptance {:.3f}",
                          d.split_rhat, d.rank_rhat, d.ess, chains * length, d.mean_acceptance);
  return d;
}

}  // namespace tb::mcmc

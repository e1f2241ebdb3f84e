// Stationarity tests (docs/validation.md E, fourth item).
//
// chi-square: `chains` chains start from exact draws of pi and apply k transitions each; the
// histogram of the final states over the target's bins is compared with the exact bin masses by
// Pearson's test (validate/chi2/pearson_gof.h; bins of zero mass that receive a state fail outright).
//
// Rank test (Gandy & Scott 2020, "Unit testing for MCMC and other Monte Carlo methods", their
// test for reversible kernels): pick M uniformly in
// {0..L-1}, draw X_M exactly from pi, run the kernel forward from X_M to X_{L-1} and, the kernel
// being reversible, also "backward" from X_M to X_0. If pi is invariant and the kernel reversible,
// (X_0..X_{L-1}) is a stationary reversible sequence independent of M, so the rank of f(X_M) among
// the f(X_t) is uniform on {0..L-1} (ties broken uniformly at random). The rank histogram over
// `replicates` runs is tested against uniform by Pearson's chi-square.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/chi2/pearson_gof.h"
#include "validate/mcmc/checker_concepts.h"

namespace tb::mcmc {

struct StationarityResult {
  int64_t chains = 0, steps = 0;
  PearsonResult pearson;
  double alpha = 0.0;
  bool passed = false;
  std::string message;
};

template <MoveKernel K, ExactTarget Tg>
StationarityResult check_stationarity_chi2(const K& kernel, const Tg& target, int64_t chains, int64_t steps,
                                           uint64_t seed, uint64_t key, double alpha) {
  const int nb = target.bin_count();
  std::vector<int> bin(chains);
  parallel_for(static_cast<size_t>(chains), [&](size_t c) {
    Rng rng = Rng::for_sample(seed, key, c);
    RngUniforms u(rng);
    typename K::State x = target.sample_exact(u);
    for (int64_t s = 0; s < steps; ++s) x = step(kernel, x, u).next();
    bin[c] = target.bin_of(x);
  });
  std::vector<double> obs(nb, 0.0), expct(nb);
  for (int b : bin) obs[b] += 1.0;
  for (int i = 0; i < nb; ++i) expct[i] = target.bin_mass(i) * static_cast<double>(chains);
  StationarityResult r;
  r.chains = chains;
  r.steps = steps;
  r.alpha = alpha;
  r.pearson = pearson_chi2_gof(obs, expct);
  r.passed = !r.pearson.rejects(alpha) && r.pearson.zero_expected_observed == 0;
  r.message = fmt::format("{} chains from exact draws, {} steps each: chi2 = {:.1f} on {} dof, p = {:.3g} (alpha {:.2g})",
                          chains, steps, r.pearson.statistic, r.pearson.dof, r.pearson.p_value, alpha);
  return r;
}

struct RankTestResult {
  int64_t replicates = 0, length = 0;
  PearsonResult pearson;
  double alpha = 0.0;
  bool passed = false;
  std::string message;
};

template <MoveKernel K, ExactTarget Tg>
RankTestResult check_gandy_scott_rank(const K& kernel, const Tg& target, int64_t replicates, int length,
                                      uint64_t seed, uint64_t key, double alpha) {
  std::vector<int> rank(replicates);
  parallel_for(static_cast<size_t>(replicates), [&](size_t i) {
    Rng rng = Rng::for_sample(seed, key, i);
    RngUniforms u(rng);
    const int m = static_cast<int>(rng.uniform_below(static_cast<uint32_t>(length)));
    const typename K::State xm = target.sample_exact(u);
    const double fm = target.summary(xm);
    int below = 0, ties = 0;
    auto visit = [&](const typename K::State& x) {
      const double f = target.summary(x);
      below += f < fm;
      ties += f == fm;
    };
    typename K::State x = xm;
    for (int t = m + 1; t < length; ++t) visit(x = step(kernel, x, u).next());
    x = xm;
    for (int t = m - 1; t >= 0; --t) visit(x = step(kernel, x, u).next());
    rank[i] = below + static_cast<int>(rng.uniform_below(static_cast<uint32_t>(ties + 1)));
  });
  std::vector<double> obs(length, 0.0), expct(length, static_cast<double>(replicates) / length);
  for (int k : rank) obs[k] += 1.0;
  RankTestResult r;
  r.replicates = replicates;
  r.length = length;
  r.alpha = alpha;
  r.pearson = pearson_chi2_gof(obs, expct);
  r.passed = !r.pearson.rejects(alpha);
  r.message = fmt::format("{} replicates of length {}: rank chi2 = {:.1f} on {} dof, p = {:.3g} (alpha {:.2g})",
                          replicates, length, r.pearson.statistic, r.pearson.dof, r.pearson.p_value, alpha);
  return r;
}

}  // namespace tb::mcmc

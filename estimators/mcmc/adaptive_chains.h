// Parallel chains sharing one regional adaptation state, deterministically (docs/mcmc.md,
// "Regional adaptation"). Otsu et al. adapt inside one chain, one visit at a time (Algorithm 1,
// lines 8-18); with C chains in parallel, the order in which their observations reach the shared
// lambda_k would depend on thread timing. Here the chains adapt in synchronous batches: every chain
// runs `steps` transitions with lambda frozen, recording (region of x, a(x -> y)) for each
// proposal (line 11), then all observations are applied to the adapter in chain order, each
// chain's in step order. The result is a function of (seed, key, chain count, batch length) only,
// bit-identical whatever the number of threads. Within a batch the kernel is a fixed
// Metropolis-Hastings kernel (reversible with respect to pi). The price: every observation of a
// batch is taken at one lambda, and a region receiving n visits in a batch makes about n / L
// updates from it; chains x steps per batch of about L x regions keeps that near one update per
// region per batch, as in Algorithm 1 (docs/mcmc.md measures what a long batch does to Eq. 5).
//
// The kernel K reads the adapter's current lambda through its mutation (a const reference held by
// the mutation); run_batch is the only place the adapter changes.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "estimators/mcmc/concepts.h"
#include "estimators/mcmc/kernel_step.h"
#include "estimators/mcmc/partition.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"

namespace tb::mcmc {

// Per-region mean acceptance probability of proposals made from the region.
struct RegionAcceptance {
  std::vector<double> sum;
  std::vector<int64_t> count;
  double mean(int r) const { return count[r] > 0 ? sum[r] / static_cast<double>(count[r]) : 0.0; }
};

template <MoveKernel K, Partition P, class Adapter>
class SynchronousAdaptiveChains {
 public:
  using State = typename K::State;
  // Chain c draws from Rng::for_sample(seed, key, c) for its whole life.
  SynchronousAdaptiveChains(const K& kernel, const P& partition, Adapter& adapter, std::vector<State> starts,
                            uint64_t seed, uint64_t key)
      : kernel_(kernel), partition_(partition), adapter_(adapter), x_(std::move(starts)) {
    for (size_t c = 0; c < x_.size(); ++c) rng_.push_back(Rng::for_sample(seed, key, c));
  }
  int chains() const { return static_cast<int>(x_.size()); }
  const std::vector<State>& states() const { return x_; }

  // One synchronous batch: `steps` transitions per chain at frozen lambda, then the observations
  // in chain order (nothing is applied for a partition that does not adapt).
  RegionAcceptance run_batch(int steps) { return run(steps, partition_.adapts()); }
  // Transitions at frozen lambda whose acceptances are only measured.
  RegionAcceptance measure(int steps) { return run(steps, false); }

 private:
  RegionAcceptance run(int steps, bool apply) {
    const size_t n = x_.size();
    std::vector<std::vector<std::pair<int, double>>> obs(n);
    parallel_for(n, [&](size_t c) {
      RngUniforms u(rng_[c]);
      obs[c].reserve(static_cast<size_t>(steps));
      for (int s = 0; s < steps; ++s) {
        const int r = partition_.region_of(x_[c]);
        const auto t = step(kernel_, x_[c], u);
        obs[c].emplace_back(r, t.acceptance);
        x_[c] = t.next();
      }
    });
    RegionAcceptance acc{std::vector<double>(partition_.regions(), 0.0),
                         std::vector<int64_t>(partition_.regions(), 0)};
    for (size_t c = 0; c < n; ++c)  // chain order, then step order: independent of threads
      for (const auto& [r, a] : obs[c]) {
        acc.sum[r] += a;
        ++acc.count[r];
        if (apply) adapter_.observe(r, a);
      }
    return acc;
  }

  const K& kernel_;
  const P& partition_;
  Adapter& adapter_;
  std::vector<State> x_;
  std::vector<Rng> rng_;
};

}  // namespace tb::mcmc

// Pairwise detailed balance on seeded proposal pairs (docs/validation.md E, second item). For each
// pair, x is an exact draw from pi (or any start sampler), the kernel proposes a move m to y, and
//   F = pi(x) q(x -> m) a(x -> m),   B = pi(y) q(y -> m') a(y -> m'),   m' = reverse(x, m)
// must agree to a relative 1e-9 (|F - B| <= 1e-9 max(F, B)). For Metropolis-Hastings q is
// c_k(x) T_k(x -> y); for multiple-try kernels, the extended-space density of tries and references.
//
// What this check can and cannot see: it proves that the acceptance is consistent with the STATED
// proposal density. A proposal whose stated density differs from what it samples (a wrong sigma, a
// wrong Jacobian determinant stated consistently) passes it; those are caught by the sampling
// checks (stationarity, flux, rank) and by the Jacobian check of rj_jacobian.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/mcmc/checker_concepts.h"

namespace tb::mcmc {

struct PairwiseBalanceResult {
  int64_t pairs = 0;            // pairs attempted
  int64_t live = 0;             // pairs with F > 0 or B > 0
  int64_t failed_proposals = 0; // proposals that returned nothing
  int64_t violations = 0;       // pairs above tolerance
  int64_t nonfinite = 0;
  int64_t zero_forward = 0;     // proposed moves whose stated forward density is 0 (errors)
  double max_rel_residual = 0.0;
  int64_t worst_index = -1;     // reproducer: Rng::for_sample(seed, key, worst_index)
  double tolerance = 1e-9;
  bool passed = false;
  std::string message;
};

template <MoveKernel K>
PairwiseBalanceResult check_pairwise_balance(const K& kernel,
                                             const std::function<typename K::State(Uniforms&)>& start,
                                             int64_t pairs, uint64_t seed, uint64_t key, double tolerance = 1e-9) {
  struct Local {
    double rel = 0.0;
    int live = 0, failed = 0, nonfinite = 0, zero_forward = 0;
  };
  std::vector<Local> out(pairs);
  parallel_for(static_cast<size_t>(pairs), [&](size_t i) {
    Rng rng = Rng::for_sample(seed, key, i);
    RngUniforms u(rng);
    const typename K::State x = start(u);
    const auto m = kernel.sample_move(x, u);
    if (!m) {
      out[i].failed = 1;
      return;
    }
    const typename K::State y = kernel.destination(*m);
    const auto mr = kernel.reverse(x, *m);
    // A move the kernel made but states it could not have made (forward density 0 into a state of
    // positive target) is an error of the proposal, counted and failed, never read as flux-free.
    if (decide(kernel.move_terms(x, *m)).status == MoveStatus::kZeroForward) {
      out[i].zero_forward = 1;
      return;
    }
    const double f = kernel.target_density(x) * kernel.move_density(x, *m) * kernel.acceptance(x, *m);
    const double b = kernel.target_density(y) * kernel.move_density(y, mr) * kernel.acceptance(y, mr);
    if (!std::isfinite(f) || !std::isfinite(b)) {
      out[i].nonfinite = 1;
      return;
    }
    const double mx = std::max(f, b);
    if (mx > 0.0) {
      out[i].live = 1;
      out[i].rel = std::abs(f - b) / mx;
    }
  });
  PairwiseBalanceResult r;
  r.pairs = pairs;
  r.tolerance = tolerance;
  for (int64_t i = 0; i < pairs; ++i) {
    r.live += out[i].live;
    r.failed_proposals += out[i].failed;
    r.nonfinite += out[i].nonfinite;
    r.zero_forward += out[i].zero_forward;
    r.violations += out[i].rel > tolerance;
    if (out[i].rel > r.max_rel_residual) {
      r.max_rel_residual = out[i].rel;
      r.worst_index = i;
    }
  }
  // At least half of the pairs must carry flux, or the check says little.
  r.passed = r.violations == 0 && r.nonfinite == 0 && r.zero_forward == 0 && 2 * r.live >= pairs;
  r.message = fmt::format("{} pairs ({} with flux, {} failed proposals): max relative |F - B| = {:.3g} (pair {}), "
                          "{} above {:.0e}, {} non-finite, {} proposed with stated forward density 0",
                          pairs, r.live, r.failed_proposals, r.max_rel_residual, r.worst_index, r.violations,
                          tolerance, r.nonfinite, r.zero_forward);
  return r;
}

}  // namespace tb::mcmc

// The Metropolis-Hastings acceptance probability (Metropolis et al. 1953; Hastings 1970) with
// state-dependent selection (Otsu et al., Sec. 3.2):
//   a(x -> y) = min(1, pi(y) c_k(y) T_k(y -> x) / (pi(x) c_k(x) T_k(x -> y))).
// The rule that forms the ratio is a policy so that validate/ can build deliberately broken
// kernels (negative controls) from the same kernel code.
#pragma once

#include <algorithm>
#include <cmath>

namespace tb::mcmc {

// min(1, num / den) with the conventions a proposal needs: nothing is accepted into a state of
// zero target density (num = 0); a move out of a state of zero density (den = 0, num > 0: a chain
// started where pi = 0) is always accepted; NaN gives 0 (never silently 1). A move whose stated
// forward density is 0 never reaches this function: decide() (chain_step.h) reports it as an error.
inline double acceptance_from(double num, double den) {
  if (!(num > 0.0)) return 0.0;
  if (!(den > 0.0)) return den == 0.0 ? 1.0 : 0.0;
  const double r = num / den;
  return std::isnan(r) ? 0.0 : std::min(1.0, r);
}

// The correct rule: forward = c_k(x) T_k(x -> y), reverse = c_k(y) T_k(y -> x).
struct HastingsRatio {
  double operator()(double pi_x, double forward, double pi_y, double reverse) const {
    return acceptance_from(pi_y * reverse, pi_x * forward);
  }
};

}  // namespace tb::mcmc

// A stationary Gaussian AR(1) process x_t = rho x_{t-1} + sqrt(1 - rho^2) e_t, e_t ~ N(0, 1): the
// known-answer input for the MCMC diagnostics. Its autocorrelation is rho^k and its integrated
// autocorrelation time tau = 1 + 2 sum_k rho^k = (1 + rho) / (1 - rho).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "lib/core/math.h"
#include "lib/core/rng.h"

namespace tb::stats {

inline double ar1_autocorrelation_time(double rho) { return (1.0 + rho) / (1.0 - rho); }

// n values of the chain started at x0 (x0 = a N(0, 1) draw gives a stationary start; pass
// start_stationary = true for that), innovations from the stream `rng` (Box-Muller pairs).
inline std::vector<double> ar1_chain(Rng& rng, double rho, int64_t n, double x0, bool start_stationary) {
  std::vector<double> out(static_cast<size_t>(n));
  double spare = 0.0;
  bool has_spare = false;
  const auto normal = [&]() {
    if (has_spare) {
      has_spare = false;
      return spare;
    }
    const double r = std::sqrt(-2.0 * std::log1p(-rng.uniform()));  // 1 - u in (0, 1]
    const double phi = 2.0 * kPi * rng.uniform();
    spare = r * std::sin(phi);
    has_spare = true;
    return r * std::cos(phi);
  };
  double x = start_stationary ? normal() : x0;
  const double s = std::sqrt(1.0 - rho * rho);
  for (auto& v : out) {
    v = x;
    x = rho * x + s * normal();
  }
  return out;
}

}  // namespace tb::stats

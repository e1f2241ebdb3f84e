// Exact detailed-balance check on a finite state space (docs/validation.md E, first item): builds the
// transition matrix P_ij = sum_k c_k(i) T_k(i -> j) a_k(i -> j) for i != j, P_ii = 1 - sum_{j != i}
// P_ij, from the kernel's exposed proposal density and acceptance (no sampling), normalises pi, and
// reports max_ij |pi_i P_ij - pi_j P_ji| and ||pi P - pi||_1. Both must be below 1e-12: P has
// entries <= 1 and pi sums to one, so rounding of n = 64 terms stays near 64 * 2^-53 ~ 1e-14.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "validate/mcmc/checker_concepts.h"

namespace tb::mcmc {

struct ExactBalanceResult {
  double max_balance_residual = 0.0;  // max_ij |pi_i P_ij - pi_j P_ji|
  int worst_i = -1, worst_j = -1;
  double stationarity_l1 = 0.0;       // ||pi P - pi||_1
  double min_diagonal = 1.0;          // P_ii >= 0 is required of a stochastic matrix
  double tolerance = 1e-12;
  bool passed = false;
  std::string message;
};

template <FiniteMixtureKernel K>
ExactBalanceResult check_exact_balance(const K& kernel, int n, double tolerance = 1e-12) {
  std::vector<double> pi(n), P(static_cast<size_t>(n) * n, 0.0);
  double z = 0.0;
  for (int i = 0; i < n; ++i) z += (pi[i] = kernel.target_density(i));
  for (double& p : pi) p /= z;
  for (int i = 0; i < n; ++i) {
    double off = 0.0;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      double pij = 0.0;
      for (int c = 0; c < kernel.components(); ++c) {
        const double q = kernel.proposal_density(c, i, j);
        if (q > 0.0) pij += q * kernel.acceptance(c, i, j);
      }
      P[static_cast<size_t>(i) * n + j] = pij;
      off += pij;
    }
    P[static_cast<size_t>(i) * n + i] = 1.0 - off;
  }
  ExactBalanceResult r;
  r.tolerance = tolerance;
  for (int i = 0; i < n; ++i) {
    r.min_diagonal = std::min(r.min_diagonal, P[static_cast<size_t>(i) * n + i]);
    for (int j = i + 1; j < n; ++j) {
      const double d = std::abs(pi[i] * P[static_cast<size_t>(i) * n + j] - pi[j] * P[static_cast<size_t>(j) * n + i]);
      if (d > r.max_balance_residual) {
        r.max_balance_residual = d;
        r.worst_i = i;
        r.worst_j = j;
      }
    }
  }
  for (int j = 0; j < n; ++j) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += pi[i] * P[static_cast<size_t>(i) * n + j];
    r.stationarity_l1 += std::abs(s - pi[j]);
  }
  r.passed = r.max_balance_residual <= tolerance && r.stationarity_l1 <= tolerance && r.min_diagonal >= -tolerance;
  r.message = fmt::format("{} states: max |pi_i P_ij - pi_j P_ji| = {:.3g} (at {}, {}), ||pi P - pi||_1 = {:.3g}, "
                          "tolerance {:.0e}",
                          n, r.max_balance_residual, r.worst_i, r.worst_j, r.stationarity_l1, tolerance);
  return r;
}

}  // namespace tb::mcmc

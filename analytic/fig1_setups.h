// The technique sets of the canonical MMIS experiments (West et al. 2022, Fig. 1), shared by the
// mmis-fig1 experiment, the mmis checks and the benchmark. Functions and parameters are our own
// choice (docs/mmis-fig1.md).
//   top:    f = fig1_two_features; a classical technique good on the left plateau, a marginal
//           technique (random centre t, x | t normal) whose marginal is good on the right peak.
//   bottom: f = fig1_three_peaks; three marginal techniques each covering only part of [0, 1]
//           (with gaps between them) and a fourth with a defensive uniform x.
#pragma once

#include <vector>

#include "analytic/classical_techniques_1d.h"
#include "analytic/integrands.h"
#include "analytic/marginal_techniques_1d.h"

namespace tb {

struct Fig1Top {
  const Integrand1D* f;
  Classical1D classical;           // good on the left feature
  ConditionalNormal1D marginal;    // marginal good on the right feature
  ConditionalNormal1D extruded;    // the classical technique extruded over t ~ U[0, 1] (for the joint plot)
};
Fig1Top make_fig1_top();

struct Fig1Bottom {
  const Integrand1D* f;
  // techniques[0..2] cover parts of [0, 1]; techniques[3] is defensive (uniform x mixed in).
  std::vector<ConditionalNormal1D> techniques;
  static constexpr int kDefensive = 3;
};
// pdf_cost_repeats > 0 makes every p(x | t) artificially expensive.
Fig1Bottom make_fig1_bottom(int pdf_cost_repeats = 0);

// Exact variance of the reference MIS (balance heuristic, exact marginals by quadrature) with
// counts[i] samples from technique i of the bottom set (docs/validation.md B).
double fig1_bottom_reference_variance(const Fig1Bottom& b, const std::vector<int>& counts);

}  // namespace tb

// Adaptive Gauss-Kronrod quadrature (Boost.Math, 61 points, relative tolerance 1e-12) over an
// interval split at given breakpoints, so that discontinuities of the integrand sit on panel edges.
// Used for the reference values of integrals, marginal densities and exact MIS variances; never
// inside an estimator under test.
#pragma once

#include <functional>
#include <vector>

namespace tb {

struct QuadratureResult {
  double value = 0.0;
  double error_estimate = 0.0;  // sum of Boost's per-panel error estimates
};

// ∫_a^b g(x) dx with panels split at the breakpoints inside (a, b).
QuadratureResult integrate_1d(const std::function<double(double)>& g, double a, double b,
                              const std::vector<double>& breakpoints = {}, double rel_tol = 1e-12);

}  // namespace tb

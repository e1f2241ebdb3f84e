// Roots of a t^2 + b t + c = 0 without cancellation (Press et al., Numerical Recipes Sec. 5.6).
#pragma once

#include <cmath>
#include <utility>

namespace tb {

// Returns false when there is no real root; otherwise t0 <= t1.
inline bool solve_quadratic(double a, double b, double c, double* t0, double* t1) {
  if (a == 0) {
    if (b == 0) return false;
    *t0 = *t1 = -c / b;
    return true;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return false;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double r0 = q / a;
  double r1 = q != 0 ? c / q : r0;
  if (r0 > r1) std::swap(r0, r1);
  *t0 = r0;
  *t1 = r1;
  return true;
}

}  // namespace tb

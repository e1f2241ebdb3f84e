// sin and cos of an angle in [-pi/4, pi/4] without a libm call, for the warps that produce such
// angles on every sample (the concentric disk map, Shirley & Chiu 1997, and through it cosine-
// hemisphere sampling of Lambertian BSDFs). A call to sincos was ~4 % of path-tracing time.
//
// Math: the Taylor series sin x = sum_k (-1)^k x^(2k+1) / (2k+1)!, cos x = sum_k (-1)^k x^(2k) /
// (2k)! (Abramowitz & Stegun 4.3.65-66), truncated after x^17 and x^16. For |x| <= pi/4 the first
// omitted terms are below (pi/4)^19 / 19! < 1e-19 and (pi/4)^18 / 18! < 3e-18, far below half
// an ulp of the results (sin x ~ x, cos x >= 0.707). Evaluated by Horner's rule in x^2; the
// leading term (x, 1) is added last, so the rounding error is about one ulp of the result: not
// bit-identical to libm, but as accurate to within an ulp (tests/core/sincos_quarter_test.cpp).
#pragma once

#include "lib/core/math.h"

namespace tb {

namespace sincos_detail {
// 1 / n!, computed by the compiler from the exact integers n! (all below 2^53 up to 18!).
constexpr double inv_factorial(int n) {
  double f = 1.0;
  for (int k = 2; k <= n; ++k) f *= k;
  return 1.0 / f;
}
}  // namespace sincos_detail

// *s = sin(x), *c = cos(x) for |x| <= pi/4 (larger |x| lose accuracy: callers reduce first).
inline void sincos_quarter(double x, double* s, double* c) {
  using sincos_detail::inv_factorial;
  const double x2 = x * x;
  // sin x = x + x^3 * (-1/3! + x^2 (1/5! - x^2 (1/7! - ...)))
  double ps = inv_factorial(17);
  ps = ps * x2 - inv_factorial(15);
  ps = ps * x2 + inv_factorial(13);
  ps = ps * x2 - inv_factorial(11);
  ps = ps * x2 + inv_factorial(9);
  ps = ps * x2 - inv_factorial(7);
  ps = ps * x2 + inv_factorial(5);
  ps = ps * x2 - inv_factorial(3);
  // cos x = 1 + x^2 * (-1/2! + x^2 (1/4! - x^2 (1/6! - ...)))
  double pc = inv_factorial(16);
  pc = pc * x2 - inv_factorial(14);
  pc = pc * x2 + inv_factorial(12);
  pc = pc * x2 - inv_factorial(10);
  pc = pc * x2 + inv_factorial(8);
  pc = pc * x2 - inv_factorial(6);
  pc = pc * x2 + inv_factorial(4);
  pc = pc * x2 - inv_factorial(2);
  *s = x + x * x2 * ps;
  *c = 1.0 + x2 * pc;
}

}  // namespace tb

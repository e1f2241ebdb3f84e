// Real roots of a polynomial in an interval by recursive isolation: the roots of p' split
// [a, b] into intervals where p is monotone, and each sign change there is a root found by
// safeguarded Newton iteration (Newton inside a shrinking bisection bracket). Every step
// stays in double and the bracket guarantees convergence; roots of even multiplicity (no sign
// change) are tangencies and are not reported.
#pragma once

#include <span>
#include <vector>

namespace tb {

// p(t) = sum_i c[i] t^i.
double eval_polynomial(std::span<const double> c, double t);

// The smallest root of p in the open interval (a, b) with a sign change, or NaN if none.
// a and b must be finite.
double first_polynomial_root(std::span<const double> c, double a, double b);

// All sign-changing roots in (a, b), ascending.
std::vector<double> polynomial_roots(std::span<const double> c, double a, double b);

}  // namespace tb

#include "lib/geometry/polynomial_roots.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lib/geometry/quadratic.h"

namespace tb {
namespace {

constexpr int kMaxDegree = 8;

// Root of p in [lo, hi] given p(lo) and p(hi) of opposite signs.
double bracketed_root(std::span<const double> c, std::span<const double> dc, double lo, double hi, double flo) {
  double t = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    const double f = eval_polynomial(c, t);
    if (f == 0) return t;
    if ((f < 0) == (flo < 0)) {
      lo = t;
      flo = f;
    } else {
      hi = t;
    }
    const double df = eval_polynomial(dc, t);
    double next = df != 0 ? t - f / df : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // Newton left the bracket: bisect
    if (next == t || hi - lo <= 4 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo), std::abs(hi)))
      return next;
    t = next;
  }
  return t;
}

void roots_rec(std::span<const double> c, double a, double b, std::vector<double>& out, bool first_only) {
  int n = static_cast<int>(c.size()) - 1;
  while (n > 0 && c[static_cast<size_t>(n)] == 0) --n;
  if (n <= 0) return;
  if (n == 1) {
    const double r = -c[0] / c[1];
    if (r > a && r < b) out.push_back(r);
    return;
  }
  if (n == 2) {
    double r0, r1;
    if (!solve_quadratic(c[2], c[1], c[0], &r0, &r1)) return;
    if (r0 > a && r0 < b) out.push_back(r0);
    if (r1 != r0 && r1 > a && r1 < b && !(first_only && !out.empty())) out.push_back(r1);
    return;
  }
  double dcoef[kMaxDegree];
  for (int i = 0; i < n; ++i) dcoef[i] = (i + 1) * c[static_cast<size_t>(i) + 1];
  const std::span<const double> dc(dcoef, static_cast<size_t>(n));
  std::vector<double> crit;
  roots_rec(dc, a, b, crit, false);
  double x0 = a, f0 = eval_polynomial(c, a);
  crit.push_back(b);
  for (double x1 : crit) {
    const double f1 = eval_polynomial(c, x1);
    if (f0 != 0 && f1 != 0 && ((f0 < 0) != (f1 < 0))) {
      out.push_back(bracketed_root(c.first(static_cast<size_t>(n) + 1), dc, x0, x1, f0));
      if (first_only) return;
    } else if (f1 == 0 && x1 < b) {
      out.push_back(x1);
      if (first_only) return;
    }
    x0 = x1;
    f0 = f1;
  }
}

}  // namespace

double eval_polynomial(std::span<const double> c, double t) {
  double r = 0;
  for (size_t i = c.size(); i-- > 0;) r = std::fma(r, t, c[i]);
  return r;
}

double first_polynomial_root(std::span<const double> c, double a, double b) {
  std::vector<double> out;
  roots_rec(c, a, b, out, true);
  return out.empty() ? std::numeric_limits<double>::quiet_NaN() : out.front();
}

std::vector<double> polynomial_roots(std::span<const double> c, double a, double b) {
  std::vector<double> out;
  roots_rec(c, a, b, out, false);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace tb

#include "validate/stats/tests.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/non_central_t.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/tools/roots.hpp>

namespace tb::stats {
namespace bm = boost::math;

double normal_cdf(double x) { return bm::cdf(bm::normal_distribution<double>(), x); }
double normal_sf(double x) { return bm::cdf(bm::complement(bm::normal_distribution<double>(), x)); }
double normal_quantile(double p) { return bm::quantile(bm::normal_distribution<double>(), p); }
double normal_two_sided_p(double z) {
  if (std::isnan(z)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(z)) return 0.0;
  return std::min(1.0, 2.0 * normal_sf(std::fabs(z)));
}
double students_t_quantile(double p, double dof) { return bm::quantile(bm::students_t_distribution<double>(dof), p); }

double students_t_two_sided_p(double t, double dof) {
  if (std::isnan(t)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(t)) return 0.0;
  const bm::students_t_distribution<double> dist(dof);
  return std::min(1.0, 2.0 * bm::cdf(bm::complement(dist, std::fabs(t))));
}

namespace {
double t_two_sided_p(double t, double dof) { return students_t_two_sided_p(t, dof); }
// A zero standard error with a non-zero difference is an infinitely significant result, with a
// zero difference no evidence at all.
double safe_ratio(double diff, double se) {
  if (se > 0.0) return diff / se;
  if (diff == 0.0) return 0.0;
  return diff > 0.0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
}
}  // namespace

TestResult z_test(double mean, double std_error, double mu0) {
  TestResult r;
  r.statistic = safe_ratio(mean - mu0, std_error);
  r.p_value = normal_two_sided_p(r.statistic);
  return r;
}

TestResult z_test_greater(double value, double std_error, double bound) {
  TestResult r;
  r.statistic = safe_ratio(value - bound, std_error);
  r.p_value = std::isinf(r.statistic) ? (r.statistic > 0 ? 0.0 : 1.0) : normal_sf(r.statistic);
  return r;
}

TestResult one_sample_t_test(double mean, double s, int64_t n, double mu0) {
  if (n < 2) throw std::invalid_argument("one_sample_t_test: n < 2");
  TestResult r;
  r.dof = static_cast<double>(n - 1);
  r.statistic = safe_ratio(mean - mu0, s / std::sqrt(static_cast<double>(n)));
  r.p_value = t_two_sided_p(r.statistic, r.dof);
  return r;
}

TestResult one_sample_t_test(const Welford& w, double mu0) { return one_sample_t_test(w.mean(), w.std_dev(), w.count(), mu0); }

TestResult welch_t_test(double mean1, double var1, int64_t n1, double mean2, double var2, int64_t n2) {
  if (n1 < 2 || n2 < 2) throw std::invalid_argument("welch_t_test: n < 2");
  const double a = var1 / static_cast<double>(n1), b = var2 / static_cast<double>(n2);
  TestResult r;
  r.statistic = safe_ratio(mean1 - mean2, std::sqrt(a + b));
  // Welch-Satterthwaite; with both variances zero the dof is undefined and irrelevant.
  const double den = a * a / static_cast<double>(n1 - 1) + b * b / static_cast<double>(n2 - 1);
  r.dof = den > 0.0 ? (a + b) * (a + b) / den : static_cast<double>(n1 + n2 - 2);
  r.p_value = t_two_sided_p(r.statistic, r.dof);
  return r;
}

TestResult welch_t_test(const Welford& a, const Welford& b) {
  return welch_t_test(a.mean(), a.variance(), a.count(), b.mean(), b.variance(), b.count());
}

TestResult binomial_test(int64_t k, int64_t n, double p) {
  if (n < 0 || k < 0 || k > n || !(p >= 0.0 && p <= 1.0)) throw std::invalid_argument("binomial_test: bad arguments");
  TestResult r;
  r.statistic = static_cast<double>(k);
  if (p == 0.0 || p == 1.0 || n == 0) {
    const bool possible = n == 0 || (p == 0.0 ? k == 0 : k == n);
    r.p_value = possible ? 1.0 : 0.0;
    return r;
  }
  const bm::binomial_distribution<double> dist(static_cast<double>(n), p);
  const double dk = static_cast<double>(k);
  const double pk = bm::pdf(dist, dk);
  const double limit = pk * (1.0 + 1e-7);
  const double mode = std::floor((static_cast<double>(n) + 1.0) * p);
  // The pmf is unimodal: the values as extreme as k on the other side of the mode form a tail.
  // Find the boundary j of that tail by bisection on the monotone side, then sum it with a CDF.
  double p_value;
  if (dk == mode || pk >= bm::pdf(dist, std::min(mode, static_cast<double>(n)))) {
    p_value = 1.0;
  } else if (dk < mode) {
    // Tail below: [0, k]; other side: [j, n] with j the smallest index > mode with pmf <= limit.
    double lo = mode, hi = static_cast<double>(n) + 1.0;  // pmf(lo) > limit, pmf(hi) "= 0"
    while (hi - lo > 1.0) {
      const double mid = std::floor(0.5 * (lo + hi));
      (bm::pdf(dist, mid) <= limit ? hi : lo) = mid;
    }
    const double upper = hi > static_cast<double>(n) ? 0.0 : bm::cdf(bm::complement(dist, hi - 1.0));
    p_value = bm::cdf(dist, dk) + upper;
  } else {
    // Tail above: [k, n]; other side: [0, j] with j the largest index < mode with pmf <= limit.
    double lo = -1.0, hi = mode;  // pmf(lo) "= 0", pmf(hi) > limit
    while (hi - lo > 1.0) {
      const double mid = std::floor(0.5 * (lo + hi));
      (bm::pdf(dist, mid) <= limit ? lo : hi) = mid;
    }
    const double lower = lo < 0.0 ? 0.0 : bm::cdf(dist, lo);
    p_value = bm::cdf(bm::complement(dist, dk - 1.0)) + lower;
  }
  r.p_value = std::min(1.0, p_value);
  return r;
}

Interval binomial_interval(int64_t k, int64_t n, double confidence) {
  using D = bm::binomial_distribution<double>;
  const double a = 0.5 * (1.0 - confidence);
  const double dk = static_cast<double>(k), dn = static_cast<double>(n);
  Interval iv;
  iv.lo = D::find_lower_bound_on_p(dn, dk, a, D::clopper_pearson_exact_interval);
  iv.hi = D::find_upper_bound_on_p(dn, dk, a, D::clopper_pearson_exact_interval);
  return iv;
}

double sidak_alpha(double alpha, int64_t m) {
  if (m <= 1) return alpha;
  return -std::expm1(std::log1p(-alpha) / static_cast<double>(m));
}

double sidak_adjust(double p_min, int64_t m) {
  if (m <= 1) return p_min;
  return std::min(1.0, -std::expm1(static_cast<double>(m) * std::log1p(-p_min)));
}

TestResult stouffer(std::span<const double> z) {
  TestResult r;
  if (z.empty()) return r;
  double sum = 0.0;
  for (double v : z) sum += v;
  r.statistic = sum / std::sqrt(static_cast<double>(z.size()));
  r.p_value = normal_two_sided_p(r.statistic);
  return r;
}

double chi_squared_sf(double x, double dof) {
  if (x <= 0.0) return 1.0;
  if (std::isinf(x)) return 0.0;
  return bm::cdf(bm::complement(bm::chi_squared_distribution<double>(dof), x));
}

TestResult sum_z2_test(std::span<const double> z) {
  TestResult r;
  if (z.empty()) return r;
  double q = 0.0;
  for (double v : z) q += v * v;
  r.statistic = q;
  r.dof = static_cast<double>(z.size());
  r.p_value = chi_squared_sf(q, r.dof);
  return r;
}

double z_test_power(double delta, double alpha) {
  const double z = normal_quantile(1.0 - 0.5 * alpha);
  return normal_cdf(delta - z) + normal_cdf(-delta - z);
}

double t_test_power(double delta, double dof, double alpha) {
  const double t = students_t_quantile(1.0 - 0.5 * alpha, dof);
  if (delta == 0.0) return alpha;
  const bm::non_central_t_distribution<double> nct(dof, delta);
  return bm::cdf(bm::complement(nct, t)) + bm::cdf(nct, -t);
}

double minimal_detectable_shift(double alpha, double power) {
  // z_test_power is increasing in delta >= 0 from alpha to 1; bracket and bisect (TOMS 748).
  if (power <= alpha) return 0.0;
  const auto g = [&](double d) { return z_test_power(d, alpha) - power; };
  double hi = normal_quantile(1.0 - 0.5 * alpha) + normal_quantile(power) + 1.0;
  while (g(hi) < 0.0) hi *= 2.0;
  std::uintmax_t iters = 200;
  const auto [a, b] = bm::tools::toms748_solve(g, 0.0, hi, bm::tools::eps_tolerance<double>(50), iters);
  return 0.5 * (a + b);
}

double minimal_detectable_bias(double std_error, double alpha, double power) {
  return minimal_detectable_shift(alpha, power) * std_error;
}

namespace {

double t_to_z_slope_exact(double dof) {
  const bm::students_t_distribution<double> st(dof);
  const bm::normal_distribution<double> n;
  const auto mean_z = [&](double delta) {
    const bm::non_central_t_distribution<double> nct(dof, delta);
    const auto f = [&](double t) {
      const double F = bm::cdf(st, t);
      if (!(F > 0.0 && F < 1.0)) return 0.0;
      return bm::quantile(n, F) * bm::pdf(nct, t);
    };
    return bm::quadrature::gauss_kronrod<double, 61>::integrate(f, -200.0, 200.0, 15, 1e-10);
  };
  constexpr double h = 0.02;  // central difference; E[z] is odd and smooth in delta
  return (mean_z(h) - mean_z(-h)) / (2.0 * h);
}

}  // namespace

double inverse_sd_bias(double dof) {
  if (!(dof > 1.0)) return std::numeric_limits<double>::infinity();
  if (dof > 1e7) return 1.0;
  return std::exp(0.5 * std::log(0.5 * dof) + std::lgamma(0.5 * (dof - 1.0)) - std::lgamma(0.5 * dof));
}

double t_to_z_slope(double dof) {
  if (!(dof > 0.0)) return 0.0;
  // Grid in u = 1/dof; u = 0 is the normal limit (slope 1).
  static const std::vector<std::pair<double, double>> grid = [] {
    std::vector<std::pair<double, double>> g{{0.0, 1.0}};
    for (double d : {200.0, 100.0, 50.0, 30.0, 20.0, 15.0, 10.0, 7.0, 5.0, 4.0, 3.0, 2.5, 2.0, 1.5, 1.0})
      g.emplace_back(1.0 / d, t_to_z_slope_exact(d));
    return g;
  }();
  const double u = std::min(1.0, 1.0 / dof);
  for (size_t i = 1; i < grid.size(); ++i)
    if (u <= grid[i].first) {
      const auto& [u0, k0] = grid[i - 1];
      const auto& [u1, k1] = grid[i];
      return k0 + (k1 - k0) * (u - u0) / (u1 - u0);
    }
  return grid.back().second;  // dof < 1: the dof-1 slope (no test here uses fewer)
}

}  // namespace tb::stats

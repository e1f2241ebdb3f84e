// One-sample Kolmogorov-Smirnov test. Boost.Math 1.74 has no Kolmogorov distribution, so this
// file is the one place that evaluates a distribution function by hand; both methods are cited.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

#include "lib/core/math.h"
#include "validate/stats/tests.h"

namespace tb::stats {
namespace {

// Marsaglia, Tsang & Wang 2003, Sec. 2: P(D_n < d) = n!/n^n * (H^n)_{kk} for an m x m matrix H,
// k = floor(n d) + 1, m = 2k - 1, h = k - n d. Entries are rescaled by 2^kScaleExp to avoid
// overflow, tracking the exponent (their mPower with eH).
constexpr int kScaleExp = 400;  // rescale when entries exceed 2^400 (doubles reach 2^1023)

void matrix_power(const Eigen::MatrixXd& a, int64_t n, Eigen::MatrixXd& result, int64_t& exponent) {
  if (n == 1) {
    result = a;
    exponent = 0;
    return;
  }
  Eigen::MatrixXd half;
  int64_t half_exp = 0;
  matrix_power(a, n / 2, half, half_exp);
  result = half * half;
  exponent = 2 * half_exp;
  if (n % 2 == 1) {
    result = (a * result).eval();
  }
  const int m = static_cast<int>(a.rows());
  if (result((m - 1) / 2, (m - 1) / 2) > std::ldexp(1.0, kScaleExp)) {
    result *= std::ldexp(1.0, -kScaleExp);
    exponent += kScaleExp;
  }
}

double mtw_cdf(int64_t n, double d) {
  const double nd = static_cast<double>(n) * d;
  const int k = static_cast<int>(std::floor(nd)) + 1;
  const int m = 2 * k - 1;
  const double h = static_cast<double>(k) - nd;
  Eigen::MatrixXd H(m, m);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) H(i, j) = (i - j + 1 >= 0) ? 1.0 : 0.0;
  for (int i = 0; i < m; ++i) {
    H(i, 0) -= std::pow(h, i + 1);
    H(m - 1, i) -= std::pow(h, m - i);
  }
  H(m - 1, 0) += (2.0 * h - 1.0 > 0.0) ? std::pow(2.0 * h - 1.0, m) : 0.0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      if (i - j + 1 > 0) H(i, j) /= std::tgamma(static_cast<double>(i - j + 2));  // /(i-j+1)!
  Eigen::MatrixXd Q;
  int64_t e = 0;
  matrix_power(H, n, Q, e);
  double s = Q(k - 1, k - 1);
  // Multiply by n!/n^n one factor at a time, rescaling to stay in range.
  for (int64_t i = 1; i <= n; ++i) {
    s *= static_cast<double>(i) / static_cast<double>(n);
    if (s < std::ldexp(1.0, -kScaleExp)) {
      s *= std::ldexp(1.0, kScaleExp);
      e -= kScaleExp;
    }
  }
  return std::clamp(std::ldexp(s, static_cast<int>(std::max<int64_t>(e, -2000))), 0.0, 1.0);
}

}  // namespace

double kolmogorov_limit_sf(double x) {
  if (x <= 0.0) return 1.0;
  if (x < 1.0) {
    // Jacobi-theta form for small x, where the alternating series converges slowly:
    // P(K <= x) = sqrt(2 pi) / x * sum_{k>=1} exp(-(2k-1)^2 pi^2 / (8 x^2)) (Kolmogorov 1933;
    // e.g. Marsaglia et al. 2003, Sec. 1).
    double cdf = 0.0;
    for (int k = 1; k <= 20; ++k) {
      const double t = static_cast<double>(2 * k - 1);
      cdf += std::exp(-t * t * kPi * kPi / (8.0 * x * x));
    }
    cdf *= std::sqrt(2.0 * kPi) / x;
    return std::clamp(1.0 - cdf, 0.0, 1.0);
  }
  double sf = 0.0;
  for (int k = 1; k <= 100; ++k) {
    const double term = std::exp(-2.0 * k * k * x * x);
    sf += (k % 2 == 1 ? 2.0 : -2.0) * term;
    if (term < 1e-18) break;
  }
  return std::clamp(sf, 0.0, 1.0);
}

double kolmogorov_cdf(int64_t n, double d) {
  if (n < 1) throw std::invalid_argument("kolmogorov_cdf: n < 1");
  if (d <= 0.5 / static_cast<double>(n)) return 0.0;  // D_n >= 1/(2n) always
  if (d >= 1.0) return 1.0;
  // The exact matrix has size 2 floor(n d) + 1: use it while that stays small, the Stephens-
  // corrected limit otherwise (its error is below 1e-3 relative for n >= 100 at the tails that
  // matter; Stephens 1970).
  const double nd = static_cast<double>(n) * d;
  if (nd < 100.0 && n <= 100000) return mtw_cdf(n, d);
  const double sn = std::sqrt(static_cast<double>(n));
  return 1.0 - kolmogorov_limit_sf((sn + 0.12 + 0.11 / sn) * d);
}

TestResult ks_test(std::vector<double> samples, const std::function<double(double)>& cdf) {
  if (samples.empty()) throw std::invalid_argument("ks_test: no samples");
  std::sort(samples.begin(), samples.end());
  const double n = static_cast<double>(samples.size());
  double d = 0.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double f = cdf(samples[i]);
    d = std::max({d, static_cast<double>(i + 1) / n - f, f - static_cast<double>(i) / n});
  }
  TestResult r;
  r.statistic = d;
  r.p_value = std::clamp(1.0 - kolmogorov_cdf(static_cast<int64_t>(samples.size()), d), 0.0, 1.0);
  return r;
}

}  // namespace tb::stats

// Hypothesis tests and their building blocks, with every distribution function taken from
// Boost.Math (normal, Student t, chi-square, binomial, non-central t); nothing here hand-writes a
// CDF or a quantile, except the Kolmogorov distribution, absent from Boost 1.74 (see ks_test).
//
// Conventions: p-values are two-sided unless the name says otherwise; a test "rejects at alpha"
// when p_value < alpha; dof is 0 for tests without degrees of freedom.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "validate/stats/welford.h"

namespace tb::stats {

struct TestResult {
  double statistic = 0.0;  // z, t, chi-square, D, or the count k
  double p_value = 1.0;
  double dof = 0.0;
  bool rejects(double alpha) const { return p_value < alpha; }
};

// ---- Normal distribution (Boost.Math thin wrappers) -------------------------------------------
double normal_cdf(double x);
// Upper tail 1 - Phi(x), accurate for large x (Boost complement).
double normal_sf(double x);
// Phi^{-1}(p) for p in (0, 1).
double normal_quantile(double p);
// Two-sided tail probability P(|Z| >= |z|) = 2 * (1 - Phi(|z|)).
double normal_two_sided_p(double z);
// Student t quantile with dof degrees of freedom.
double students_t_quantile(double p, double dof);
// Two-sided tail probability P(|T| >= |t|) of Student's t with dof degrees of freedom.
double students_t_two_sided_p(double t, double dof);

// ---- Tests on means --------------------------------------------------------------------------
// Two-sided z test of H0: E[mean] = mu0 given the standard error of mean.
// statistic = (mean - mu0) / std_error.
TestResult z_test(double mean, double std_error, double mu0);
// One-sided z test of H0: value <= bound against value > bound; p = 1 - Phi((value - bound) / se).
// Used for "Var <= B" (docs/validation.md D).
TestResult z_test_greater(double value, double std_error, double bound);
// Two-sided one-sample t test of H0: mu = mu0, t = (mean - mu0) / (s / sqrt(n)), dof = n - 1.
TestResult one_sample_t_test(double mean, double s, int64_t n, double mu0);
TestResult one_sample_t_test(const Welford& w, double mu0);
// Welch's two-sample t test of H0: mu1 = mu2 for unequal variances (var = unbiased sample
// variances), dof by Welch-Satterthwaite: (v1/n1 + v2/n2)^2 / ((v1/n1)^2/(n1-1) + (v2/n2)^2/(n2-1)).
// Welch 1947; used per pixel by Jung et al. 2020.
TestResult welch_t_test(double mean1, double var1, int64_t n1, double mean2, double var2, int64_t n2);
TestResult welch_t_test(const Welford& a, const Welford& b);

// ---- Counts and distributions ----------------------------------------------------------------
// Exact two-sided binomial test of H0: success probability p given k successes in n trials: the
// p-value is the sum of P(X = j) over all j with P(X = j) <= P(X = k) * (1 + 1e-7) (the
// relative tolerance absorbs rounding so that ties count as "as extreme", as in R's binom.test).
// statistic = k.
TestResult binomial_test(int64_t k, int64_t n, double p);
// Two-sided Clopper-Pearson interval for a binomial proportion at the given confidence.
struct Interval {
  double lo = 0.0, hi = 0.0;
  bool contains(double v) const { return lo <= v && v <= hi; }
  double half_width() const { return 0.5 * (hi - lo); }
};
Interval binomial_interval(int64_t k, int64_t n, double confidence);

// One-sample Kolmogorov-Smirnov test of samples against a continuous CDF. statistic = D_n =
// sup |F_n - F|. p-value P(D_n >= d): exact by Marsaglia, Tsang & Wang 2003 ("Evaluating
// Kolmogorov's distribution", J. Stat. Softw. 8(18)) while n*d is small enough for their matrix
// power, otherwise the limiting Kolmogorov distribution at (sqrt(n) + 0.12 + 0.11/sqrt(n)) d
// (Stephens 1970 correction). samples is taken by value (it is sorted).
TestResult ks_test(std::vector<double> samples, const std::function<double(double)>& cdf);
// P(D_n < d) for the one-sample KS statistic (see ks_test for the method).
double kolmogorov_cdf(int64_t n, double d);
// Limiting distribution P(sqrt(n) D_n > x) = 2 sum_{k>=1} (-1)^(k-1) exp(-2 k^2 x^2) (Kolmogorov 1933).
double kolmogorov_limit_sf(double x);

// ---- Multiple comparisons and combined tests -------------------------------------------------
// Per-test level that keeps the family-wise error at alpha over m independent tests:
// alpha' = 1 - (1 - alpha)^(1/m) = -expm1(log1p(-alpha) / m) (Šidák 1967), stable for tiny alpha.
double sidak_alpha(double alpha, int64_t m);
// Family-wise p-value of the smallest of m p-values: 1 - (1 - p_min)^m = -expm1(m * log1p(-p_min)).
double sidak_adjust(double p_min, int64_t m);
// Stouffer's combined z: Z = sum z_i / sqrt(P), two-sided normal p-value (uniform-sign bias;
// docs/validation.md A, global tests of Jung et al. 2020).
TestResult stouffer(std::span<const double> z);
// Sum of squares Q = sum z_i^2 against chi-square with P dof, upper-tail p-value (mixed-sign bias).
TestResult sum_z2_test(std::span<const double> z);
// Upper-tail chi-square p-value P(X >= x), X ~ chi2(dof).
double chi_squared_sf(double x, double dof);

// ---- Power --------------------------------------------------------------------------------------
// Power of the two-sided z test at level alpha against a true shift of delta standard errors:
// Phi(delta - z) + Phi(-delta - z), z = Phi^{-1}(1 - alpha/2).
double z_test_power(double delta, double alpha);
// Power of the two-sided one-sample t test (dof = n - 1) against a shift of delta standard errors,
// from the non-central t distribution (Boost.Math non_central_t).
double t_test_power(double delta, double dof, double alpha);
// Smallest shift (in standard errors) the two-sided z test detects with the given power:
// solves z_test_power(delta, alpha) = power (docs/validation.md A: "smallest bias detected at 90%").
double minimal_detectable_shift(double alpha, double power = 0.9);
// The same in units of the estimate: minimal_detectable_shift(alpha, power) * std_error.
double minimal_detectable_bias(double std_error, double alpha, double power = 0.9);
// The slope of the image comparison's z-scores in the true shift, for a t statistic with `dof`
// degrees of freedom mapped to the normal quantile of the same tail, z(t) = Phi^{-1}(F_dof(t)):
//     kappa(dof) = d/d delta E[z(T_delta)] at delta = 0,
// T_delta non-central t with non-centrality delta (a true shift of delta standard errors). A
// small shift of delta standard errors moves the mean of z by kappa delta: 0.83 at dof 1, 0.94 at
// 4, 0.99 at 30, 1 in the limit. Computed by Gauss-Kronrod quadrature of z(t) against the
// non-central t density (Boost.Math) on a grid in 1/dof, interpolated linearly in 1/dof.
double t_to_z_slope(double dof);
// E[sigma / s] for a standard deviation s estimated with `dof` degrees of freedom
// (s^2 ~ sigma^2 chi2_dof / dof): sqrt(dof / 2) Gamma((dof - 1) / 2) / Gamma(dof / 2), > 1, so
// 1 / s overestimates 1 / sigma by this factor; infinite for dof <= 1.
double inverse_sd_bias(double dof);

}  // namespace tb::stats

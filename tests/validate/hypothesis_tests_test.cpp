// Known p-values of each test against tabulated values (tables of the normal, t and chi-square
// quantiles; exact binomial sums; R's binom.test documentation example; Marsaglia, Tsang & Wang
// 2003 for the Kolmogorov distribution).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/stats/tests.h"

namespace tb::stats {
namespace {

TEST(Normal, TabulatedQuantiles) {
  EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 1e-12);
  EXPECT_NEAR(normal_cdf(1.959963984540054), 0.975, 1e-14);
  EXPECT_NEAR(normal_two_sided_p(2.5758293035489), 0.01, 1e-12);
  EXPECT_NEAR(normal_sf(10.0), 7.619853024160527e-24, 1e-36);  // accurate far tail
}

TEST(ZTest, TwoSidedAndOneSided) {
  const TestResult r = z_test(1.0 + 1.959963984540054 * 0.1, 0.1, 1.0);
  EXPECT_NEAR(r.statistic, 1.959963984540054, 1e-12);
  EXPECT_NEAR(r.p_value, 0.05, 1e-12);
  EXPECT_NEAR(z_test_greater(1.0 + 1.6448536269514722, 1.0, 1.0).p_value, 0.05, 1e-12);
  EXPECT_DOUBLE_EQ(z_test(2.0, 0.0, 1.0).p_value, 0.0);
  EXPECT_DOUBLE_EQ(z_test(1.0, 0.0, 1.0).p_value, 1.0);
}

TEST(TTest, TabulatedCriticalValues) {
  // t_{0.975, 10} = 2.228138852; t_{0.995, 4} = 4.604094871.
  const TestResult r = one_sample_t_test(2.228138852 * 3.0 / std::sqrt(11.0), 3.0, 11, 0.0);
  EXPECT_DOUBLE_EQ(r.dof, 10.0);
  EXPECT_NEAR(r.p_value, 0.05, 1e-9);
  EXPECT_NEAR(one_sample_t_test(4.604094871, std::sqrt(5.0), 5, 0.0).p_value, 0.01, 1e-9);
  EXPECT_NEAR(students_t_quantile(0.975, 10), 2.228138852, 1e-9);
}

TEST(WelchTest, ReducesToPooledTWithEqualSizesAndVariances) {
  const TestResult r = welch_t_test(1.0, 4.0, 11, 0.0, 4.0, 11);
  EXPECT_NEAR(r.dof, 20.0, 1e-12);  // 2 (n - 1)
  EXPECT_NEAR(r.statistic, 1.0 / std::sqrt(8.0 / 11.0), 1e-12);
  // Unequal: Welch-Satterthwaite dof = (0.1 + 0.2)^2 / (0.1^2/9 + 0.2^2/19) = 27.98...
  const TestResult u = welch_t_test(0.0, 1.0, 10, 1.0, 4.0, 20);
  EXPECT_NEAR(u.dof, 0.09 / (0.01 / 9.0 + 0.04 / 19.0), 1e-12);
  EXPECT_NEAR(u.statistic, -1.0 / std::sqrt(0.3), 1e-12);
  // |t| = 2.048407 is t_{0.975, 28}: p ~= 0.05 at dof ~= 28.
  const TestResult c = welch_t_test(2.048407142 * std::sqrt(0.3), 1.0, 10, 0.0, 4.0, 20);
  EXPECT_NEAR(c.p_value, 0.05, 2e-4);
}

TEST(BinomialTest, ExactSums) {
  // Symmetric p = 1/2: p-value = 2 P(X <= 3) = 2 * 176 / 1024.
  EXPECT_NEAR(binomial_test(3, 10, 0.5).p_value, 0.34375, 1e-12);
  EXPECT_NEAR(binomial_test(9, 10, 0.5).p_value, 22.0 / 1024.0, 1e-12);
  EXPECT_NEAR(binomial_test(5, 10, 0.5).p_value, 1.0, 1e-12);
  // R: binom.test(682, 925, p = 0.75) gives p-value = 0.3825.
  EXPECT_NEAR(binomial_test(682, 925, 0.75).p_value, 0.3825, 5e-5);
  // Asymmetric, lower tail: n = 20, p = 0.3, k = 1: P(X<=1) + P(X >= j) where j is the first
  // index above the mode with pmf <= pmf(1) = 20 * 0.3 * 0.7^19 = 0.0068393.
  // pmf(12) = 0.0039 <= pmf(1) < pmf(11) = 0.0120: p = P(X<=1) + P(X>=12).
  const double p1 = std::pow(0.7, 20) + 20 * 0.3 * std::pow(0.7, 19);
  double upper = 0.0, c = 1.0;
  for (int j = 0; j <= 20; ++j) {
    if (j > 0) c = c * (20 - j + 1) / j;
    if (j >= 12) upper += c * std::pow(0.3, j) * std::pow(0.7, 20 - j);
  }
  EXPECT_NEAR(binomial_test(1, 20, 0.3).p_value, p1 + upper, 1e-12);
  EXPECT_DOUBLE_EQ(binomial_test(0, 10, 0.0).p_value, 1.0);
  EXPECT_DOUBLE_EQ(binomial_test(1, 10, 0.0).p_value, 0.0);
}

TEST(BinomialInterval, ClopperPearson) {
  const Interval iv = binomial_interval(5, 10, 0.95);
  // Clopper-Pearson 95% for 5/10: [0.187086, 0.812914].
  EXPECT_NEAR(iv.lo, 0.187086, 1e-6);
  EXPECT_NEAR(iv.hi, 0.812914, 1e-6);
}

TEST(Kolmogorov, ExactAndLimit) {
  // Marsaglia, Tsang & Wang 2003: K(10, 0.274) = 0.6284796154565043.
  EXPECT_NEAR(kolmogorov_cdf(10, 0.274), 0.6284796154565043, 1e-13);
  // n = 1: D_1 = max(U, 1 - U) is uniform on [1/2, 1].
  EXPECT_NEAR(kolmogorov_cdf(1, 0.8), 0.6, 1e-13);
  // Tabulated critical values of the limit: P(K > 1.3581) = 0.05, P(K > 1.6276) = 0.01.
  EXPECT_NEAR(kolmogorov_limit_sf(1.35810), 0.05, 2e-5);
  EXPECT_NEAR(kolmogorov_limit_sf(1.62762), 0.01, 2e-5);
  // Both branches of the limit agree at x = 1.
  EXPECT_NEAR(kolmogorov_limit_sf(1.0 - 1e-12), kolmogorov_limit_sf(1.0), 1e-10);
  // Exact at n = 1000 against the Stephens-corrected limit.
  const double sn = std::sqrt(1000.0);
  EXPECT_NEAR(kolmogorov_cdf(1000, 1.35810 / (sn + 0.12 + 0.11 / sn)), 0.95, 1e-3);
}

TEST(KsTest, UniformSamplesAcceptedShiftedRejected) {
  const auto uniform_cdf = [](double x) { return std::clamp(x, 0.0, 1.0); };
  int rejections = 0;
  for (uint64_t rep = 0; rep < 20; ++rep) {
    Rng rng = Rng::for_sample(5, 0x65, rep);
    std::vector<double> xs(500);
    for (double& x : xs) x = rng.uniform();
    rejections += ks_test(xs, uniform_cdf).p_value < 0.01;
  }
  EXPECT_LE(rejections, 2);  // P(>= 3 of 20 at 1%) ~ 1e-3
  // Negative control: samples of x^1.2 are not uniform.
  Rng rng(17);
  std::vector<double> ys(2000);
  for (double& y : ys) y = std::pow(rng.uniform(), 1.2);
  EXPECT_LT(ks_test(ys, uniform_cdf).p_value, 1e-6);
}

TEST(Sidak, StableAndInverse) {
  EXPECT_DOUBLE_EQ(sidak_alpha(0.05, 1), 0.05);
  EXPECT_NEAR(sidak_alpha(0.05, 10), 1.0 - std::pow(0.95, 0.1), 1e-15);
  EXPECT_NEAR(sidak_alpha(0.05, 10), 0.0051161968, 1e-10);
  // Tiny alpha over many tests, where 1 - (1 - a)^(1/m) in floating point loses digits.
  const double a = sidak_alpha(1e-12, 1000000);
  EXPECT_NEAR(a, 1e-18, 1e-27);
  EXPECT_NEAR(sidak_adjust(sidak_alpha(1e-3, 100), 100), 1e-3, 1e-15);
}

TEST(CombinedTests, StoufferAndSumZ2) {
  const std::vector<double> z = {1.0, 2.0, -0.5, 1.5};
  const TestResult s = stouffer(z);
  EXPECT_NEAR(s.statistic, 4.0 / 2.0, 1e-15);
  EXPECT_NEAR(s.p_value, normal_two_sided_p(2.0), 1e-15);
  const TestResult q = sum_z2_test(std::vector<double>{1.959963984540054});
  EXPECT_NEAR(q.p_value, 0.05, 1e-12);
  // chi2_{0.95, 4} = 9.487729037.
  EXPECT_NEAR(chi_squared_sf(9.487729037, 4), 0.05, 1e-9);
}

TEST(Power, ZAndT) {
  const double z = 2.5758293035489;
  EXPECT_NEAR(z_test_power(4.0, 0.01), normal_cdf(4.0 - z) + normal_cdf(-4.0 - z), 1e-15);
  EXPECT_NEAR(z_test_power(4.0, 0.01), 0.9228, 1e-4);
  EXPECT_NEAR(z_test_power(0.0, 0.05), 0.05, 1e-14);
  // 90% power at alpha = 0.05 needs delta ~= z_{0.975} + z_{0.9} = 3.2415 (+ a negligible other tail).
  const double d = minimal_detectable_shift(0.05, 0.9);
  EXPECT_NEAR(z_test_power(d, 0.05), 0.9, 1e-12);
  EXPECT_NEAR(d, 1.959963984540054 + 1.2815515655446004, 1e-6);
  EXPECT_NEAR(minimal_detectable_bias(0.01, 0.05, 0.9), 0.01 * d, 1e-15);
  // t power approaches z power for large dof and is smaller for small dof.
  EXPECT_NEAR(t_test_power(4.0, 1e6, 0.01), z_test_power(4.0, 0.01), 1e-4);
  EXPECT_LT(t_test_power(4.0, 10, 0.01), z_test_power(4.0, 0.01));
  EXPECT_NEAR(t_test_power(0.0, 10, 0.01), 0.01, 1e-12);
}

}  // namespace
}  // namespace tb::stats

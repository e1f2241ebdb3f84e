// The error measures of `tb compare SCENE --integrators ...` (app/compare_metrics.h,
// docs/compare.md): rRMSE and its floor, the reference's own noise, Satterthwaite's effective
// term count, error maps, checkpoint budgets and the text table; and the rate fit the command
// runs on its checkpoints (stats::fit_time_power_law) on exact and noisy power laws.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "app/compare_metrics.h"
#include "lib/core/rng.h"
#include "validate/stats/convergence_fit.h"

namespace tb {
namespace {

std::vector<Rgb> ramp(size_t n) {
  std::vector<Rgb> r(n);
  for (size_t i = 0; i < n; ++i) r[i] = Rgb(1.0 + double(i), 2.0 + 0.5 * double(i), 0.25 + double(i % 7));
  return r;
}

TEST(CompareMetrics, ConstantRelativeErrorIsTheRrmse) {
  const std::vector<Rgb> ref = ramp(50);
  std::vector<Rgb> img = ref;
  for (Rgb& v : img) v *= 1.03;
  const auto e = compare::relative_error(img, ref, {}, 0.0);
  EXPECT_EQ(e.channels, 150);
  EXPECT_EQ(e.below_floor, 0);
  EXPECT_NEAR(e.rrmse, 0.03, 1e-12);
  EXPECT_NEAR(e.mean_relative, 0.03, 1e-12);
  EXPECT_NEAR(e.median_abs_relative, 0.03, 1e-12);
  EXPECT_EQ(e.rrmse_ref, 0.0);
  // All terms equal: Satterthwaite's k is the number of terms.
  EXPECT_NEAR(e.effective_terms, 150.0, 1e-6);
}

TEST(CompareMetrics, RelMseWithEpsilonMatchesItsDefinition) {
  // (x - r)^2 / (r^2 + 0.01) averaged over every pixel-channel, dark ones included.
  const std::vector<Rgb> ref = {Rgb(1.0, 0.0, 0.5), Rgb(2.0, 0.1, 0.0)};
  const std::vector<Rgb> img = {Rgb(1.1, 0.2, 0.5), Rgb(1.0, 0.1, std::numeric_limits<double>::quiet_NaN())};
  const double expect = (0.01 / 1.01 + 0.04 / 0.01 + 0.0 + 1.0 / 4.01 + 0.0) / 5.0;  // NaN left out
  EXPECT_NEAR(compare::relmse_eps(img, ref), expect, 1e-12);
  EXPECT_EQ(compare::relmse_eps(ref, ref), 0.0);
}

TEST(CompareMetrics, FloorLeavesOutDarkChannelsAndCountsThem) {
  std::vector<Rgb> ref = ramp(10), img = ref;
  ref[3] = Rgb(0.0, 1e-9, 5.0);
  img[3] = Rgb(1.0, 1.0, 5.0 * 1.1);  // huge relative error on the dark channels: must not count
  const double floor = compare::reference_floor(ref, 0.01);
  EXPECT_GT(floor, 1e-9);
  const auto e = compare::relative_error(img, ref, {}, floor);
  EXPECT_EQ(e.below_floor, 2);
  EXPECT_EQ(e.channels, 28);
  EXPECT_NEAR(e.rrmse, std::sqrt(0.01 / 28.0), 1e-12);
  EXPECT_EQ(e.median_abs_relative, 0.0);  // one outlier moves rRMSE, not the median
}

TEST(CompareMetrics, NonFiniteRenderValuesAreCountedNotUsed) {
  const std::vector<Rgb> ref = ramp(4);
  std::vector<Rgb> img = ref;
  img[1].g = std::numeric_limits<double>::quiet_NaN();
  img[2].b = std::numeric_limits<double>::infinity();
  const auto e = compare::relative_error(img, ref, {}, 0.0);
  EXPECT_EQ(e.nonfinite, 2);
  EXPECT_EQ(e.channels, 10);
  EXPECT_EQ(e.rrmse, 0.0);
}

TEST(CompareMetrics, ReferenceNoiseIsReportedSeparately) {
  const std::vector<Rgb> ref = ramp(20);
  std::vector<Rgb> var(ref.size());
  for (size_t i = 0; i < ref.size(); ++i) var[i] = (0.1 * ref[i]) * (0.1 * ref[i]);  // 10% relative sd
  const auto e = compare::relative_error(ref, ref, var, 0.0);
  EXPECT_NEAR(e.rrmse_ref, 0.1, 1e-12);
  EXPECT_EQ(e.rrmse, 0.0);
}

// Gaussian relative noise of sd sigma on K = 3 * 20000 channels: rRMSE estimates sigma with
// standard error sigma / sqrt(2K) (chi-square with K dof); 6 standard errors (two-sided
// p ~ 2e-9) with a fixed seed. Satterthwaite's k for equal variances from one render: the
// expected value of (sum e^2)^2 / sum e^4 is about K / 3 (E e^4 = 3 sigma^4).
TEST(CompareMetrics, GaussianNoiseGivesItsSigma) {
  const size_t n = 20000;
  const double sigma = 0.2;
  const std::vector<Rgb> ref = ramp(n);
  std::vector<Rgb> img(n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      Rng rng = Rng::for_sample(7, 11, i * 3 + size_t(c));
      const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);  // Box-Muller
      img[i][c] = ref[i][c] * (1.0 + sigma * z);
    }
  const auto e = compare::relative_error(img, ref, {}, 0.0);
  const double K = 3.0 * double(n);
  EXPECT_NEAR(e.rrmse, sigma, 6.0 * sigma / std::sqrt(2.0 * K));
  EXPECT_NEAR(e.effective_terms / K, 1.0 / 3.0, 0.02);
  // Median of |z| sigma: sigma Phi^-1(3/4) = 0.6745 sigma; its standard error is
  // sqrt(1/4) / (f sqrt(K)) with f = 2 phi(0.6745) = 0.636 the density of |z| there: 0.79 sigma /
  // sqrt(K). Six standard errors, as above.
  EXPECT_NEAR(e.median_abs_relative, 0.67449 * sigma, 6.0 * 0.79 * sigma / std::sqrt(K));
}

TEST(CompareMetrics, ErrorMapAndColours) {
  std::vector<Rgb> ref = {Rgb(1.0), Rgb(0.0), Rgb(2.0, 0.0, 2.0)};
  std::vector<Rgb> img = {Rgb(1.5), Rgb(3.0), Rgb(1.0, 9.0, 3.0)};
  const auto m = compare::relative_error_map(img, ref, 0.0);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_NEAR(m[0], 0.5, 1e-15);
  EXPECT_EQ(m[1], -1.0);  // no channel above the floor
  EXPECT_NEAR(m[2], 0.5, 1e-15);
  const auto c = compare::heat_colours({0.0, 1.0, 10.0, -1.0}, 1.0);
  EXPECT_EQ(c[0], Rgb(0.0));
  EXPECT_EQ(c[1], Rgb(1.0));
  EXPECT_EQ(c[2], Rgb(1.0));
  EXPECT_EQ(c[3], Rgb(0.0, 0.0, 0.05));
}

TEST(CompareMetrics, CheckpointBudgetsHalve) {
  const auto t = compare::checkpoint_budgets(8.0, 5);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t, (std::vector<double>{0.5, 1.0, 2.0, 4.0, 8.0}));
}

TEST(CompareMetrics, TextTablePadsColumns) {
  const std::string s = compare::text_table({"name", "x"}, {{"pt", "1.5"}, {"pssmlt", "10"}});
  EXPECT_EQ(s, "name      x\n-----------\npt      1.5\npssmlt   10\n");
}

// The fit the command runs: an exact power law rRMSE = 2 t^-0.5 returns alpha = 0.5; a noisy one
// (log-normal scatter of sd 1 / sqrt(2k), as the weights assume) covers 0.5 in its 99% interval.
TEST(CompareMetrics, TimeFitRecoversTheRate) {
  std::vector<stats::ConvergencePoint> exact, noisy;
  const double k = 2000.0;
  for (int i = 0; i < 5; ++i) {
    stats::ConvergencePoint p;
    p.n = p.seconds = 0.5 * std::ldexp(1.0, i);
    p.rmse = 2.0 / std::sqrt(p.seconds);
    p.replicates = int64_t(k);
    exact.push_back(p);
    Rng rng = Rng::for_sample(3, 5, uint64_t(i));
    const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
    const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    p.rmse *= std::exp(z / std::sqrt(2.0 * k));
    noisy.push_back(p);
  }
  const auto f = stats::fit_time_power_law(exact);
  EXPECT_TRUE(f.converged);
  EXPECT_NEAR(f.alpha, 0.5, 1e-9);
  const auto g = stats::fit_time_power_law(noisy);
  EXPECT_LE(g.alpha_lo, 0.5);
  EXPECT_GE(g.alpha_hi, 0.5);
}

}  // namespace
}  // namespace tb

#include "validate/stats/convergence_fit.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/rng.h"

namespace tb::stats {
namespace {

std::vector<ConvergencePoint> synthetic(double c, double alpha, double b, int64_t reps) {
  std::vector<ConvergencePoint> pts;
  for (int k = 4; k <= 16; ++k) {
    ConvergencePoint p;
    p.n = std::ldexp(1.0, k);
    p.rmse = std::sqrt(c * c * std::pow(p.n, -2.0 * alpha) + b * b);
    p.replicates = reps;
    p.seconds = 1e-6 * p.n;
    pts.push_back(p);
  }
  return pts;
}

TEST(ConvergenceFit, ExactPowerLaw) {
  const auto pts = synthetic(0.7, 0.5, 0.0, 64);
  const PowerLawFit fit = fit_power_law(pts);
  ASSERT_TRUE(fit.converged);
  EXPECT_NEAR(fit.alpha, 0.5, 1e-8);
  EXPECT_NEAR(std::exp(fit.log_c), 0.7, 1e-7);
  EXPECT_FALSE(fit.rescaled);
  // Whitened residual sd 1/sqrt(2R): se(alpha) = 1 / (sqrt(2R) sqrt(sum (ln N - mean)^2)).
  double mean = 0, sxx = 0;
  for (const auto& p : pts) mean += std::log(p.n) / static_cast<double>(pts.size());
  for (const auto& p : pts) sxx += (std::log(p.n) - mean) * (std::log(p.n) - mean);
  EXPECT_NEAR(fit.alpha_std_error, 1.0 / std::sqrt(128.0 * sxx), 1e-6);
  EXPECT_LT(fit.half_width(), 0.03);
  const PowerLawFit tfit = fit_time_power_law(pts);
  EXPECT_NEAR(tfit.alpha, 0.5, 1e-8);
  EXPECT_NEAR(efficiency(pts[0]), 1.0 / (pts[0].rmse * pts[0].rmse * pts[0].seconds), 1e-9);
}

TEST(ConvergenceFit, FloorRecovered) {
  const auto pts = synthetic(0.5, 0.5, 3e-3, 64);
  const FloorFit fit = fit_power_law_with_floor(pts);
  ASSERT_TRUE(fit.converged);
  EXPECT_NEAR(fit.b, 3e-3, 1e-7);
  EXPECT_NEAR(fit.alpha, 0.5, 1e-6);
  EXPECT_TRUE(fit.floor_detected());
  const FloorFit none = fit_power_law_with_floor(synthetic(0.5, 0.5, 0.0, 64));
  EXPECT_FALSE(none.floor_detected());
  EXPECT_NEAR(none.b, 0.0, 1e-6);
}

TEST(ConvergenceFit, StudyOfPlainMonteCarlo) {
  // Mean of N uniforms estimates 1/2 with RMSE = sqrt(1/12) N^-1/2.
  const Estimator est = [](int64_t n, uint64_t seed) {
    Rng rng(seed);
    double s = 0;
    for (int64_t i = 0; i < n; ++i) s += rng.uniform();
    return s / static_cast<double>(n);
  };
  ConvergenceStudyOptions o;
  o.log2_max = 12;
  o.replicates = 64;
  o.seed = 3;
  const ConvergenceStudy s = run_convergence_study(est, 0.5, o);
  ASSERT_EQ(s.points.size(), 9u);
  EXPECT_GT(s.fit.alpha_hi, 0.5);
  EXPECT_LT(s.fit.alpha_lo, 0.5);
  EXPECT_NEAR(std::exp(s.fit.log_c), std::sqrt(1.0 / 12.0), 0.1 * std::sqrt(1.0 / 12.0));
  EXPECT_FALSE(s.floor_fit.floor_detected());
  const PlotSpec plot = convergence_plot("mc", s.points, &s.fit, &s.floor_fit);
  EXPECT_EQ(plot.series.size(), 3u);
  EXPECT_TRUE(plot.log_x && plot.log_y);
}

}  // namespace
}  // namespace tb::stats

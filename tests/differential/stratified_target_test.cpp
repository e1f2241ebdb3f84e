// Unit tests of lib/mcmc/stratified_target (Zirr & Dachsbacher 2020, Eq. 8 and its footnote,
// Eq. 22): the two forms of the target agree, and on a one-dimensional path space with a closed
// form the target integrates to the stated normalisation E_p[min{r~, S / B}].
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "lib/core/rng.h"
#include "lib/mcmc/stratified_target.h"

namespace tb::mcmc {
namespace {

// Midpoint rule on [0, 1].
double integrate(const std::function<double(double)>& g, int n = 1 << 20) {
  double s = 0.0;
  for (int i = 0; i < n; ++i) s += g((i + 0.5) / n);
  return s / n;
}

TEST(StratifiedTarget, FootnoteFormEqualsDefinition) {
  Rng rng = Rng::for_sample(1, 0x5747, 0);
  for (int i = 0; i < 10000; ++i) {
    const double f = std::exp(8.0 * (rng.uniform() - 0.5)), p = std::exp(8.0 * (rng.uniform() - 0.5));
    const double r = 1.0 + std::exp(10.0 * (rng.uniform() - 0.5)), B = std::exp(6.0 * (rng.uniform() - 0.5));
    const double w = stratified_target(f, p, r, B);
    EXPECT_NEAR(w, f / bounded_splat(f / p, r, B), 1e-12 * w);
    EXPECT_NEAR(normalisation_sample(f / p, r, B), w / p, 1e-12 * w / p);
    EXPECT_LE(w, f / B * (1 + 1e-15));
    EXPECT_LE(w, p * r * (1 + 1e-15));
  }
  EXPECT_EQ(stratified_target(0.0, 1.0, 2.0, 1.0), 0.0);
}

// X in [0, 1], p(x) = 1, f(x) = 3x^2 (so B = integral of f = 1).
double f1(double x) { return 3.0 * x * x; }

TEST(StratifiedTarget, IntegratesToClosedFormNormalisation) {
  const double B = 1.0;
  // r~ = 1: W~ = min{1, 3x^2}, integral 1 - 2 / (3 sqrt 3).
  const double exact1 = 1.0 - 2.0 / (3.0 * std::sqrt(3.0));
  EXPECT_NEAR(integrate([&](double x) { return stratified_target(f1(x), 1.0, 1.0, B); }), exact1, 1e-9);
  // r~ = 1 + x: W~ = min{1 + x, 3x^2}, crossing at x0 = (1 + sqrt 13) / 6:
  // integral x0^3 + (1 + 1/2) - (x0 + x0^2 / 2).
  const double x0 = (1.0 + std::sqrt(13.0)) / 6.0;
  const double exact2 = x0 * x0 * x0 + 1.5 - (x0 + 0.5 * x0 * x0);
  const auto r2 = [](double x) { return 1.0 + x; };
  EXPECT_NEAR(integrate([&](double x) { return stratified_target(f1(x), 1.0, r2(x), B); }), exact2, 1e-9);
  // The stated bounds: <= integral of f / B = 1 and <= E_p[r~] = 3/2.
  EXPECT_LT(exact2, 1.0);
  EXPECT_LT(exact1, 1.0);

  // The normalisation estimated as stated, E_p[min{r~, S / B}] over x ~ p, with B itself from a pilot.
  Rng rng = Rng::for_sample(1, 0x5748, 0);
  const int n = 1 << 18;
  std::vector<double> pilot(n);
  for (double& s : pilot) s = f1(rng.uniform());
  const double b_hat = pilot_brightness(pilot);
  EXPECT_NEAR(b_hat, 1.0, 5.0 * std::sqrt(9.0 / 5.0 - 1.0) / std::sqrt(n));  // Var[3x^2] = 9/5 - 1
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = rng.uniform();
    const double w = normalisation_sample(f1(x), r2(x), B);
    sum += w;
    sum2 += w * w;
  }
  const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
  EXPECT_NEAR(mean, exact2, 5.0 * se);
}

TEST(StratifiedTarget, PixelValuesFromTargetAndSplats) {
  // I_j = (integral of W~) E_{pi~}[h_j S~] = integral of h_j W~ S~ = integral of h_j f, pixels of width 1/4.
  const double B = 1.0;
  const auto r = [](double x) { return 1.0 + 4.0 * x; };
  for (int j = 0; j < 4; ++j) {
    const auto h = [j](double x) { return (x >= j / 4.0 && x < (j + 1) / 4.0) ? 1.0 : 0.0; };
    const double via_target = integrate([&](double x) {
      return h(x) * stratified_target(f1(x), 1.0, r(x), B) * bounded_splat(f1(x), r(x), B);
    });
    const double exact = (std::pow((j + 1) / 4.0, 3) - std::pow(j / 4.0, 3));
    EXPECT_NEAR(via_target, exact, 1e-9);
  }
}

TEST(StratifiedTarget, AcceptanceAndSplats) {
  // r~ = 1 and B below every splat: S~ = S, W~ = p (Sec. 4.2), Eq. 22 is MH on p.
  const double px = 0.5, py = 2.0, fx = 1.0, fy = 3.0, B = 1e-6;
  const double wx = stratified_target(fx, px, 1.0, B), wy = stratified_target(fy, py, 1.0, B);
  EXPECT_DOUBLE_EQ(wx, px);
  EXPECT_DOUBLE_EQ(wy, py);
  const double a = stratified_acceptance(wx, 0.3, wy, 0.1);
  EXPECT_NEAR(a, std::min(1.0, py * 0.1 / (px * 0.3)), 1e-15);
  const StratifiedSplats s = stratified_splats(bounded_splat(fx / px, 1.0, B), bounded_splat(fy / py, 1.0, B), a);
  EXPECT_DOUBLE_EQ(s.proposal, (fy / py) * a);
  EXPECT_DOUBLE_EQ(s.current, (fx / px) * (1 - a));
  EXPECT_DOUBLE_EQ(stratified_acceptance(0.0, 1.0, 1.0, 1.0), 1.0);
}

}  // namespace
}  // namespace tb::mcmc

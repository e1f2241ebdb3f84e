// The stated power of the image comparison (validate/image_compare.h, min_detectable_relative_bias;
// docs/statistics.md "What a passing check rules out"):
//  - t_to_z_slope against a Monte Carlo estimate of d E[z(T)] / d delta at dof 4 and 30;
//  - on synthetic Gaussian images (16 x 16, 4 and 8 Welch samples per pixel on each side, one
//    tested channel, and three independent ones), a bias of the stated size is rejected in at
//    least 90% of 300 seeded pairs (the rate's 99% Clopper-Pearson interval reaches 0.9),
//    per-pixel and tiled;
//  - negative control: half the stated bias is rejected significantly less often than 90%, so a
//    statement twice too optimistic would be caught.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/image_compare.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

constexpr int kSize = 16;

double normal(Rng& rng) {
  const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Welch samples N(f mu, (0.3 mu)^2) per pixel and channel, channels independent; with
// `one_channel`, G and B are 0 (skipped as identical), so only R is tested.
WelchImage gaussian_image(uint64_t seed, int passes, double f, bool one_channel = false) {
  WelchImage w(kSize, kSize);
  for (size_t i = 0; i < w.pixels(); ++i) {
    Rng rng = Rng::for_sample(seed, i, 0);
    const Rgb mu(0.5 + 0.02 * double(i % kSize), 0.3 + 0.01 * double(i / kSize), 0.8);
    for (int p = 0; p < passes; ++p) {
      Rgb s(0.0);
      for (int c = 0; c < 3; ++c) s[c] = f * mu[c] + 0.3 * mu[c] * normal(rng);
      if (one_channel) s[1] = s[2] = 0.0;
      w.add(i, s);
    }
  }
  return w;
}

TEST(ImageComparePower, TToZSlopeMatchesMonteCarlo) {
  EXPECT_DOUBLE_EQ(stats::t_to_z_slope(1e9), 1.0 - (1.0 - stats::t_to_z_slope(200.0)) * 200.0 / 1e9);
  EXPECT_NEAR(stats::t_to_z_slope(1.0), 0.83, 0.01);
  for (double dof : {1.0, 2.0, 4.0, 10.0, 30.0, 100.0}) EXPECT_LT(stats::t_to_z_slope(dof), stats::t_to_z_slope(dof * 1.5));
  // Monte Carlo: T = (Z + delta) / sqrt(chi2_dof / dof), z(T) = Phi^{-1}(F_dof(T)), antithetic in delta.
  for (int dof : {4, 30}) {
    Rng rng = Rng::for_sample(77, uint64_t(dof), 0);
    constexpr int kN = 200000;
    constexpr double kDelta = 0.25;
    double sum = 0.0, sum_sq = 0.0;
    for (int k = 0; k < kN; ++k) {
      const double z = normal(rng);
      double chi2 = 0.0;
      for (int j = 0; j < dof; ++j) {
        const double n = normal(rng);
        chi2 += n * n;
      }
      const double scale = 1.0 / std::sqrt(chi2 / dof);
      const auto zt = [&](double t) {
        const double p = stats::students_t_two_sided_p(t, dof);
        const double a = p >= 1.0 ? 0.0 : stats::normal_quantile(1.0 - 0.5 * p);
        return t < 0 ? -a : a;
      };
      const double d = (zt((z + kDelta) * scale) - zt((z - kDelta) * scale)) / (2.0 * kDelta);
      sum += d;
      sum_sq += d * d;
    }
    const double mean = sum / kN, se = std::sqrt((sum_sq / kN - mean * mean) / kN);
    // The slope at delta = 0.25 differs from the one at 0 by O(delta^2) (E[z] is odd in delta).
    EXPECT_NEAR(mean, stats::t_to_z_slope(dof), 4.0 * se + 0.005) << "dof " << dof;
  }
}

TEST(ImageComparePower, UniformBiasMdeIgnoresTestsWithoutSignalOrLevel) {
  const double one = uniform_bias_mde({{2.0, 1e-3}});
  EXPECT_NEAR(one * 2.0, stats::minimal_detectable_shift(1e-3, 0.9), 1e-9);
  // A channel with no tested unit has gain 0 and level 0: no power, no error.
  EXPECT_DOUBLE_EQ(uniform_bias_mde({{2.0, 1e-3}, {0.0, 0.0}, {0.0, 1e-3}}), one);
  EXPECT_FALSE(std::isfinite(uniform_bias_mde({{0.0, 0.0}})));
  // Two equal independent tests need a smaller bias than one.
  EXPECT_LT(uniform_bias_mde({{2.0, 1e-3}, {2.0, 1e-3}}), one);
}

struct PowerRun {
  double mde = 0;
  int rejects_at_mde = 0, rejects_at_half = 0, replicates = 0;
};

PowerRun measure(int passes, const ImageCompareOptions& options, bool one_channel, bool independent) {
  constexpr double kAlpha = 0.01;
  PowerRun r;
  r.replicates = 300;
  // The stated bias of an unbiased pair (it depends on the standard errors only, so one pair
  // fixes it up to noise).
  const ImageCompareResult unbiased = compare_welch_images(gaussian_image(5, passes, 1.0, one_channel),
                                                           gaussian_image(6, passes, 1.0, one_channel), kAlpha, options);
  r.mde = independent ? unbiased.min_detectable_relative_bias_independent : unbiased.min_detectable_relative_bias;
  for (int k = 0; k < r.replicates; ++k) {
    const WelchImage b = gaussian_image(20000 + uint64_t(k), passes, 1.0, one_channel);
    r.rejects_at_mde +=
        compare_welch_images(gaussian_image(10000 + uint64_t(k), passes, 1.0 + r.mde, one_channel), b, kAlpha, options).rejects();
    r.rejects_at_half += compare_welch_images(gaussian_image(10000 + uint64_t(k), passes, 1.0 + 0.5 * r.mde, one_channel), b,
                                              kAlpha, options)
                             .rejects();
  }
  return r;
}

void expect_power(const PowerRun& r, const char* what) {
  SCOPED_TRACE(what);
  std::printf("%s: stated bias %.4g, rejected in %d / %d at it, %d / %d at half of it\n", what, r.mde, r.rejects_at_mde,
              r.replicates, r.rejects_at_half, r.replicates);
  ASSERT_TRUE(std::isfinite(r.mde) && r.mde > 0.0) << r.mde;
  const auto at = stats::binomial_interval(r.rejects_at_mde, r.replicates, 0.99);
  const auto half = stats::binomial_interval(r.rejects_at_half, r.replicates, 0.99);
  EXPECT_GE(at.hi, 0.9) << "stated bias " << r.mde << " rejected in " << r.rejects_at_mde << " of " << r.replicates;
  // Negative control: a statement of half the size would not hold.
  EXPECT_LT(half.hi, 0.9) << "half the stated bias rejected in " << r.rejects_at_half << " of " << r.replicates;
}

// One tested channel: the stated bias is exact there (the headline, valid for any dependence
// between channels, and the independent-channel figure coincide).
TEST(ImageComparePower, StatedBiasIsDetectedAtNinetyPercentAndHalfOfItIsNot) {
  expect_power(measure(8, {}, true, false), "one channel, per pixel, 8 Welch samples");
  expect_power(measure(4, {}, true, false), "one channel, per pixel, 4 Welch samples");
  ImageCompareOptions tiled;
  tiled.test = CompareTest::kTiled;
  tiled.tile = 4;
  expect_power(measure(8, tiled, true, false), "one channel, 4x4 tiles, 8 Welch samples");
  // Three independent channels: the independent-channel figure is exact there; the headline
  // (best channel alone) is conservative.
  expect_power(measure(8, {}, false, true), "three independent channels (independent figure), per pixel, 8");
  const PowerRun headline = measure(8, {}, false, false);
  std::printf("three channels, headline: stated bias %.4g, rejected in %d / %d\n", headline.mde, headline.rejects_at_mde,
              headline.replicates);
  EXPECT_GE(stats::binomial_interval(headline.rejects_at_mde, headline.replicates, 0.99).hi, 0.9);
}

}  // namespace
}  // namespace tb

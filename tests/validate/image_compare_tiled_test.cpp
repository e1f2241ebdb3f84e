// The tiled Welch test (validate/image_compare.h, docs/statistics.md "Heavy tails: the tiled Welch
// test") on synthetic heavy-tailed images: a short render (16 Welch samples of 8 lognormal raw
// samples per pixel) against one of 8x the effort (16 Welch samples of 64), same means.
//  - false alarms of the tiled test at alpha = 0.01 over 200 seeded pairs: the rate's 99%
//    Clopper-Pearson interval contains 0.01 (or lies below it: the combination is conservative);
//  - a 5% bias of the short render (its samples scaled by 1.05) rejected in >= 95% of the pairs;
//  - negative control: the per-pixel test rejects most of the same correct pairs, from skew alone.
#include <cmath>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/image_compare.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

constexpr int kSize = 16;
constexpr double kSigma = 1.0;  // lognormal shape: skewness (e^s2 + 2) sqrt(e^s2 - 1) = 6.18, finite variance

// Welch samples of per-pixel, per-channel mean mu: each the average of `per_pass` raw samples
// mu * exp(sigma N - sigma^2 / 2) (mean mu), channels independent.
WelchImage lognormal_image(uint64_t seed, int passes, int per_pass) {
  WelchImage w(kSize, kSize);
  for (size_t i = 0; i < w.pixels(); ++i) {
    Rng rng = Rng::for_sample(seed, i, 0);
    const Rgb mu(0.5 + 0.02 * double(i % kSize), 0.3 + 0.01 * double(i / kSize), 0.8);
    for (int p = 0; p < passes; ++p) {
      Rgb s(0.0);
      for (int k = 0; k < per_pass; ++k)
        for (int c = 0; c < 3; ++c) {
          const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
          const double n = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
          s[c] += mu[c] * std::exp(kSigma * n - 0.5 * kSigma * kSigma);
        }
      w.add(i, s / double(per_pass));
    }
  }
  return w;
}

// The same Welch samples times f (a render biased by the factor f).
WelchImage scaled(WelchImage w, double f) {
  for (size_t i = 0; i < w.pixels(); ++i) {
    w.sum[i] *= f;
    w.sum_sq[i] *= f * f;
    w.sum_cu[i] *= f * f * f;
  }
  return w;
}

ImageCompareOptions tiled() {
  ImageCompareOptions o;
  o.test = CompareTest::kTiled;
  return o;
}

TEST(ImageCompareTiled, HeavyTailedPairsFalseAlarmRatePowerAndPerPixelNegativeControl) {
  constexpr int kReplicates = 200;
  constexpr double kAlpha = 0.01;
  int tiled_rejects = 0, pixel_rejects = 0, biased_rejects = 0;
  double sum_z_tiled = 0, sum_z_pixel = 0;
  int k_min = 1 << 30, k_max = 0;
  for (int r = 0; r < kReplicates; ++r) {
    const WelchImage a = lognormal_image(1000 + uint64_t(r), 16, 8);
    const WelchImage b = lognormal_image(90000 + uint64_t(r), 16, 64);
    const ImageCompareResult t = compare_welch_images(a, b, kAlpha, tiled());
    const ImageCompareResult p = compare_welch_images(a, b, kAlpha);
    const ImageCompareResult biased = compare_welch_images(scaled(a, 1.05), b, kAlpha, tiled());
    EXPECT_TRUE(t.tiled && t.tile_from_skewness && t.third_moments);
    EXPECT_TRUE(t.skew_condition_met()) << t.predicted_shift;
    k_min = std::min(k_min, t.tile);
    k_max = std::max(k_max, t.tile);
    tiled_rejects += t.rejects();
    pixel_rejects += p.rejects();
    biased_rejects += biased.rejects();
    sum_z_tiled += t.stouffer.statistic;
    sum_z_pixel += p.stouffer.statistic;
  }
  const stats::Interval ci = stats::binomial_interval(tiled_rejects, kReplicates, 0.99);
  std::printf("tiled: %d / %d false alarms (99%% CI [%.4f, %.4f]), k in [%d, %d], mean worst-channel Z %.3f; "
              "per-pixel: %d / %d, mean Z %.3f; 5%% bias: %d / %d rejected\n",
              tiled_rejects, kReplicates, ci.lo, ci.hi, k_min, k_max, sum_z_tiled / kReplicates, pixel_rejects,
              kReplicates, sum_z_pixel / kReplicates, biased_rejects, kReplicates);
  EXPECT_LE(ci.lo, kAlpha) << "tiled false-alarm rate above alpha";
  EXPECT_GE(biased_rejects, (95 * kReplicates) / 100) << "5% bias not rejected often enough";
  // Negative control: the per-pixel test is invalid here (predicted shift ~ 3 c sqrt(P), c ~ 0.09).
  EXPECT_GE(pixel_rejects, kReplicates / 2) << "the per-pixel test should reject these correct pairs";
}

TEST(ImageCompareTiled, SymmetricSamplesNeedNoTilesAndOldFilesFallBack) {
  // Equal effort: the third cumulants of the two means cancel, so k = 1 is valid.
  const WelchImage a = lognormal_image(7, 16, 16), b = lognormal_image(8, 16, 16);
  EXPECT_LE(tile_skew_shift(a, b, 1), 0.25 + 0.5);  // noise of the k3 estimates only
  // Without third moments (an EXR written before moment3): the fallback k, reported as such.
  WelchImage c = a;
  c.sum_cu.clear();
  const ImageCompareResult r = compare_welch_images(c, b, 0.01, tiled());
  EXPECT_FALSE(r.third_moments);
  EXPECT_FALSE(r.tile_from_skewness);
  EXPECT_EQ(r.tile, 8);
  EXPECT_EQ(r.tested, 3 * 4);  // (16 / 8)^2 tiles per channel
  // A given k is used as given; the whole image is the last candidate.
  ImageCompareOptions o = tiled();
  o.tile = 4;
  EXPECT_EQ(compare_welch_images(a, b, 0.01, o).tested, 3 * 16);
  EXPECT_EQ(choose_tile(a, b, 0.0), kSize);
}

TEST(ImageCompareTiled, TileStatisticIsTheWelchTestOfTileSums) {
  // 2x1 image, one tile: t = (sum of mean differences) / sqrt(sum of squared standard errors).
  WelchImage a(2, 1), b(2, 1);
  for (double x : {1.0, 2.0, 4.0}) a.add(0, Rgb(x)), a.add(1, Rgb(2 * x));
  for (double x : {1.0, 1.5, 2.0, 3.0}) b.add(0, Rgb(x)), b.add(1, Rgb(x));
  ImageCompareOptions o = tiled();
  o.tile = 2;
  const ImageCompareResult r = compare_welch_images(a, b, 0.01, o);
  ASSERT_EQ(r.tested, 3);
  const double d = (7.0 / 3 - 1.875) + (14.0 / 3 - 1.875);
  const double va = a.variance(0).r / 3 + a.variance(1).r / 3, vb = 2 * b.variance(0).r / 4;
  EXPECT_NEAR(r.worst.t, d / std::sqrt(va + vb), 1e-12);
  const double dof = (va + vb) * (va + vb) /
                     ((a.variance(0).r / 3) * (a.variance(0).r / 3) / 2 + (a.variance(1).r / 3) * (a.variance(1).r / 3) / 2 +
                      2 * (b.variance(0).r / 4) * (b.variance(0).r / 4) / 3);
  EXPECT_NEAR(r.worst.dof, dof, 1e-9);
}

}  // namespace
}  // namespace tb

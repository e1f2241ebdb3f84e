// The Welch image comparison (validate/image_compare.h): accepts two independent unbiased noisy
// images and rejects a 2% bias (the negative control), at alpha = 0.01, seeded.
#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "validate/image_compare.h"

namespace tb {
namespace {

// Raw samples mu(x, y, c) * Exp(1) noise (or 2 U(0,1), symmetric); a Welch sample averages 8
// of them (one pass).
Film noisy_image(uint64_t seed, double scale, bool symmetric = false) {
  Film film(24, 16);
  for (int pass = 0; pass < 32; ++pass) {
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 24; ++x)
        for (int s = 0; s < 8; ++s) {
          Rng rng = Rng::for_sample(seed, uint64_t(pass), uint64_t((y * 24 + x) * 8 + s));
          const Rgb mu(0.2 + 0.03 * x, 0.5 + 0.05 * y, 1.0);
          Rgb noise(-std::log1p(-rng.uniform()), -std::log1p(-rng.uniform()), -std::log1p(-rng.uniform()));
          if (symmetric) noise = 2.0 * Rgb(rng.uniform(), rng.uniform(), rng.uniform());
          film.add_sample({x + 0.5, y + 0.5}, scale * mu * noise, 0);
        }
    film.end_pass();
  }
  return film;
}

TEST(FilmCompare, AcceptsIndependentUnbiasedImages) {
  const auto r = compare_welch_images(noisy_image(1, 1.0).welch(), noisy_image(2, 1.0).welch(), 0.01);
  EXPECT_FALSE(r.rejects()) << r.message();
  EXPECT_EQ(r.tested, 24 * 16 * 3);
}

TEST(FilmCompare, NegativeControlRejectsTwoPercentBias) {
  const auto r = compare_welch_images(noisy_image(1, 1.02).welch(), noisy_image(2, 1.0).welch(), 0.01);
  EXPECT_TRUE(r.rejects_stouffer()) << r.message();
  EXPECT_GT(r.stouffer.statistic, 0.0);
}

TEST(FilmCompare, KnownReferenceAndZeroVarianceCases) {
  // Against an exact reference the test is one-sample; skewed Welch samples (Gamma(8)) make
  // the t statistics skewed and Stouffer's sum over 1152 of them notices, so this case uses
  // symmetric noise (docs/film.md).
  const Film a = noisy_image(3, 1.0, true);
  WelchImage ref(24, 16);  // exact reference: one Welch sample per pixel, the true mean
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) ref.add(size_t(y * 24 + x), Rgb(0.2 + 0.03 * x, 0.5 + 0.05 * y, 1.0));
  const auto known = compare_welch_images(a.welch(), ref, 0.01);
  EXPECT_FALSE(known.rejects()) << known.message();
  WelchImage c1(1, 1), c2(1, 1);
  for (int i = 0; i < 3; ++i) {
    c1.add(0, Rgb(1.0));
    c2.add(0, Rgb(1.0, 1.0, 2.0));
  }
  const auto r = compare_welch_images(c1, c2, 0.01);
  EXPECT_EQ(r.skipped_identical, 2);
  EXPECT_EQ(r.zero_variance_mismatch, 1);
  EXPECT_TRUE(r.rejects());
  // Means of ~1e-40 with zero variance (an EXR's float variance of such values underflows): not
  // testable, skipped; the same zero-variance mismatch at 1e-18 still rejects.
  WelchImage t1(1, 1), t2(1, 1), u1(1, 1), u2(1, 1);
  for (int i = 0; i < 3; ++i) {
    t1.add(0, Rgb(1e-40, 0.0, 0.0));
    t2.add(0, Rgb(2e-38, 0.0, 0.0));
    u1.add(0, Rgb(1e-18, 0.0, 0.0));
    u2.add(0, Rgb(2e-18, 0.0, 0.0));
  }
  t1.set_from_moments(0, t1.mean(0), Rgb(0.0), 3);
  t2.set_from_moments(0, t2.mean(0), Rgb(0.0), 3);
  u1.set_from_moments(0, u1.mean(0), Rgb(0.0), 3);
  u2.set_from_moments(0, u2.mean(0), Rgb(0.0), 3);
  const auto tiny = compare_welch_images(t1, t2, 0.01);
  EXPECT_EQ(tiny.skipped_below_float_range, 1);
  EXPECT_FALSE(tiny.rejects()) << tiny.message();
  const auto small = compare_welch_images(u1, u2, 0.01);
  EXPECT_EQ(small.zero_variance_mismatch, 1);
  EXPECT_TRUE(small.rejects());
}

}  // namespace
}  // namespace tb

// Third moments of Welch samples (WelchImage, EXR moment3.*) and the skew-corrected comparison
// (Hall's transformation, validate/image_compare.h): a heavy-tailed render with few Welch samples
// against a long reference of the same mean is pushed to a negative Stouffer Z by skew alone; the
// transformation must shrink that false signal and must still reject a real 5% bias.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/film/exr_io.h"
#include "validate/image_compare.h"

namespace tb {
namespace {

// Welch samples of per-pixel mean mu: each averages `per_pass` raw samples that are 0 with
// probability 1 - q and mu / q otherwise (rare bright contributions, skewness ~ 1/sqrt(q)).
WelchImage rare_events(uint64_t seed, int passes, int per_pass, double scale, double q = 0.05) {
  WelchImage w(32, 32);
  for (size_t i = 0; i < w.pixels(); ++i) {
    const double mu = 0.5 + 0.01 * double(i % 32);
    for (int p = 0; p < passes; ++p) {
      double s = 0.0;
      for (int k = 0; k < per_pass; ++k) {
        Rng rng = Rng::for_sample(seed, i, uint64_t(p * per_pass + k));
        if (rng.uniform() < q) s += scale * mu / q;
      }
      w.add(i, Rgb(s / per_pass));
    }
  }
  return w;
}

TEST(FilmSkew, ThirdCentralMomentMatchesTheDefinitionAndSurvivesExr) {
  WelchImage w(2, 1);
  for (double x : {1.0, 2.0, 6.0}) w.add(0, Rgb(x, 2 * x, -x));
  for (double x : {3.0, 3.0, 3.0, 3.0}) w.add(1, Rgb(x));
  // mean 3, deviations -2, -1, 3: m3 = (-8 - 1 + 27) / 3 = 6.
  EXPECT_NEAR(w.third_central_moment(0).r, 6.0, 1e-12);
  EXPECT_NEAR(w.third_central_moment(0).g, 48.0, 1e-12);
  EXPECT_NEAR(w.third_central_moment(0).b, -6.0, 1e-12);
  EXPECT_NEAR(w.third_central_moment(1).r, 0.0, 1e-12);
  const std::string path = (std::filesystem::temp_directory_path() / "tb_film_skew_test.exr").string();
  write_exr(path, exr_image_from_welch(w));
  const WelchImage back = welch_from_exr_image(read_exr(path));
  ASSERT_TRUE(back.has_third_moment());
  EXPECT_NEAR(back.third_central_moment(0).g, 48.0, 1e-4);
  EXPECT_NEAR(back.mean(0).r, 3.0, 1e-6);
  // An EXR without moment3 gives an image without a third moment (no correction possible).
  ExrImage e = exr_image_from_welch(w);
  e.moment3.reset();
  write_exr(path, e);
  EXPECT_FALSE(welch_from_exr_image(read_exr(path)).has_third_moment());
  std::filesystem::remove(path);
}

TEST(FilmSkew, HallTransformIsMonotoneAndIdentityWithoutSkew) {
  EXPECT_EQ(hall_transform(1.7, 0.0), 1.7);
  for (double c : {-0.3, -0.05, 0.05, 0.3})
    for (double t = -6; t < 6; t += 0.01) EXPECT_LE(hall_transform(t, c), hall_transform(t + 0.01, c) + 1e-12);
}

TEST(FilmSkew, CorrectionShrinksTheSkewSignalAndKeepsABiasVisible) {
  const WelchImage reference = rare_events(7, 64, 64, 1.0);  // long: nearly exact
  const WelchImage test = rare_events(8, 16, 16, 1.0);       // few, skewed Welch samples
  ImageCompareOptions on;
  on.skew_correction = true;
  const auto plain = compare_welch_images(test, reference, 0.01);
  const auto corrected = compare_welch_images(test, reference, 0.01, on);
  ASSERT_TRUE(corrected.skew_corrected);
  // Same means, but skew alone gives a clearly negative Stouffer Z without the correction.
  EXPECT_LT(plain.stouffer.statistic, -3.0) << plain.message();
  EXPECT_LT(std::abs(corrected.stouffer.statistic), 0.5 * std::abs(plain.stouffer.statistic)) << plain.message() << "\n" << corrected.message();
  // Negative control: a 5% bias is still rejected with the correction.
  const auto biased = compare_welch_images(rare_events(8, 16, 16, 1.05), reference, 0.01, on);
  EXPECT_TRUE(biased.rejects()) << biased.message();
}

}  // namespace
}  // namespace tb

// Pixel groups for heavy-tailed MCMC image comparisons (validate/render/pixel_groups.h).
#include "validate/render/pixel_groups.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "lib/core/rng.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

std::vector<Rgb> ramp_image(int w, int h) {
  std::vector<Rgb> img(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img[size_t(y * w + x)] = Rgb(0.01 + (x == 3 && y == 2 ? 25.0 : 0.0) + 0.1 * y);
  return img;
}

TEST(PixelGroups, EveryGroupHoldsTheMinimumShare) {
  const int w = 16, h = 16;
  const std::vector<Rgb> img = ramp_image(w, h);
  double total = 0;
  for (const Rgb& c : img) total += luminance(c);
  for (double share : {0.01, 0.05, 0.2, 1.0}) {
    const std::vector<int> g = group_pixels_by_share(img, w, h, share);
    const int n = group_count(g);
    ASSERT_GE(n, 1);
    std::vector<double> sum(size_t(n), 0.0);
    for (size_t i = 0; i < img.size(); ++i) {
      ASSERT_GE(g[i], 0);
      ASSERT_LT(g[i], n);
      sum[size_t(g[i])] += luminance(img[i]);
    }
    for (double s : sum) EXPECT_GE(s, share * total * (1 - 1e-12)) << "share " << share;
    // Not much coarser than needed: fewer than 1/share groups, more than half of them.
    EXPECT_LE(n, static_cast<int>(1.0 / share + 1e-9));
    if (share < 1.0) {
      EXPECT_GE(n, static_cast<int>(0.5 / share) - 1);
    }
  }
  // The bright pixel (25, about 11 % of the image) is a group of its own at share 0.05.
  const std::vector<int> g = group_pixels_by_share(img, w, h, 0.05);
  int same = 0;
  for (int v : g) same += v == g[2 * w + 3];
  EXPECT_EQ(same, 1);
}

TEST(PixelGroups, MortonBlocksAtUniformBrightness) {
  // Uniform image, share 1/16 of 8 x 8: 16 groups of 4 pixels, each a 2 x 2 block.
  const std::vector<Rgb> img(64, Rgb(1.0));
  const std::vector<int> g = group_pixels_by_share(img, 8, 8, 1.0 / 16.0);
  EXPECT_EQ(group_count(g), 16);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_EQ(g[size_t(y * 8 + x)], g[size_t((y & ~1) * 8 + (x & ~1))]);
}

TEST(PixelGroups, ZeroReferenceIsOneGroup) {
  const std::vector<Rgb> img(12, Rgb(0.0));
  EXPECT_EQ(group_count(group_pixels_by_share(img, 4, 3, 0.1)), 1);
  EXPECT_THROW(group_pixels_by_share(img, 4, 4, 0.1), std::invalid_argument);
}

TEST(PixelGroups, FilmObserverFeedsGroupSums) {
  Film film(4, 2);
  std::vector<int> groups = {0, 0, 1, 1, 0, 0, 1, 2};
  GroupedWelch gw(groups);
  gw.attach(film);
  for (int pass = 0; pass < 3; ++pass) {
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 4; ++x)
        film.add_sample(Vec2(x + 0.5, y + 0.5), Rgb(double(pass + 1) * (x + 4 * y + 1)), uint64_t(pass));
    film.end_pass();
  }
  gw.detach(film);
  film.end_pass();  // no longer observed
  ASSERT_EQ(gw.welch().pixels(), 3u);
  // Pixel values v = x + 4y + 1 per unit pass weight: group 0 = 1+2+5+6 = 14, group 1 = 3+4+7 = 14, group 2 = 8.
  const double passes_sum = 1 + 2 + 3;
  EXPECT_DOUBLE_EQ(gw.welch().sum[0].x, 14 * passes_sum);
  EXPECT_DOUBLE_EQ(gw.welch().sum[1].y, 14 * passes_sum);
  EXPECT_DOUBLE_EQ(gw.welch().sum[2].z, 8 * passes_sum);
  EXPECT_EQ(gw.welch().count[0], 3);
  EXPECT_EQ(film.welch().count[0], 4);
}

// The reason for grouping: a pixel carried by about one chain in C (a mode the chains rarely
// enter) makes the per-pixel Welch test reject far more often than alpha, while sums over groups
// holding >= 16 expected carriers keep it near alpha. Synthetic chains: 64 pixels of mean m;
// pixel 0 is a dim "rare" mode of mean m / 10: in a chain it is 0, or with probability q = 1 / C
// it is carried by that chain with value (m / 10) / q (one carrier per image on average); the
// other pixels are Gaussian around m. The reference is Gaussian around the exact means.
// Rejection rates over 400 replicates at alpha = 0.01.
TEST(PixelGroups, GroupingRestoresTheLevelOfHeavyTailedPixels) {
  const int P = 64, C = 128, R = 400;
  const double alpha = 0.01, share = 1.0 / P, rare = share / 10.0, q = 1.0 / C;
  std::vector<Rgb> ref_mean(P, Rgb(share));
  ref_mean[0] = Rgb(rare);
  const std::vector<int> groups = group_pixels_by_share(ref_mean, 8, 8, 16.0 / C);
  int reject_pixel = 0, reject_group = 0;
  for (int r = 0; r < R; ++r) {
    Rng rng = Rng::for_sample(17, 0x9e0u, uint64_t(r));
    auto normal = [&] {
      const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    };
    WelchImage a(8, 8), b(8, 8);
    GroupedWelch ga(groups), gb(groups);
    std::vector<Rgb> pass(P);
    for (int c = 0; c < C; ++c) {
      for (int i = 0; i < P; ++i)
        pass[size_t(i)] = Rgb(i == 0 ? (rng.uniform() < q ? rare / q : 0.0) : share * (1.0 + 0.3 * normal()));
      for (int i = 0; i < P; ++i) a.add(size_t(i), pass[size_t(i)]);
      ga.add_pass(pass);
    }
    for (int c = 0; c < 32; ++c) {
      for (int i = 0; i < P; ++i) pass[size_t(i)] = Rgb((i == 0 ? rare : share) * (1.0 + 0.3 * normal()));
      for (int i = 0; i < P; ++i) b.add(size_t(i), pass[size_t(i)]);
      gb.add_pass(pass);
    }
    reject_pixel += compare_channels(a, b, alpha).rejects();
    reject_group += compare_channels(ga.welch(), gb.welch(), alpha).rejects();
  }
  // Measured: per pixel about 0.6 of the replicates, grouped about alpha.
  EXPECT_GT(reject_pixel, R / 4);
  EXPECT_LT(reject_group, R / 20);
  std::printf("rejections in %d replicates: per pixel %d, grouped %d\n", R, reject_pixel, reject_group);
  RecordProperty("reject_pixel", reject_pixel);
  RecordProperty("reject_group", reject_group);
}

}  // namespace
}  // namespace tb

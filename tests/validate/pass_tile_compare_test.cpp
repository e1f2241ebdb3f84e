// The pass-tile comparison (validate/pass_tile_compare.h) on synthetic renders whose tiles are
// dependent within a pass the way an MCMC pass makes them: a pass splats M visits of a chain over
// 64 tiles (multinomial with the tiles' shares), scaled by a per-pass normalisation estimate b_p,
// so tiles compete for one budget and share one random scale. Size (false alarms at alpha 0.05
// over 400 pairs, one-sided binomial test at 1e-3) and power (a 10% bias of B in one bright tile,
// caught in at least 90% of 200 pairs of 32 passes) are checked; the per-pixel independence the tiled Welch
// test assumes does not hold in this data.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "lib/film/pass_tiles.h"
#include "validate/pass_tile_compare.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

constexpr int kW = 16, kH = 16;  // 8 x 8 tiles of 2 x 2 pixels

// Pixel shares of the synthetic image: one bright 2 x 2 block, the rest dim with a gradient.
std::vector<double> shares() {
  std::vector<double> s(kW * kH);
  double total = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      double v = 1.0 + 0.2 * x + 0.1 * y;
      if (x >= 4 && x < 6 && y >= 4 && y < 6) v = 40.0;
      s[size_t(y * kW + x)] = v;
      total += v;
    }
  for (double& v : s) v /= total;
  return s;
}

// One render of `passes` passes; `bias` multiplies what the bright block receives.
PassTiles render(std::mt19937_64& rng, int passes, double bias) {
  const std::vector<double> w = shares();
  std::discrete_distribution<int> pick(w.begin(), w.end());
  std::lognormal_distribution<double> b(0.0, 0.05);
  PassTiles t(kW, kH);
  constexpr int kVisits = 4000;
  for (int p = 0; p < passes; ++p) {
    std::vector<Rgb> img(size_t(kW * kH), Rgb(0.0));
    const double bp = b(rng);
    for (int m = 0; m < kVisits; ++m) img[size_t(pick(rng))] += Rgb(bp / kVisits, 0.5 * bp / kVisits, 0.25 * bp / kVisits);
    for (int y = 4; y < 6; ++y)
      for (int x = 4; x < 6; ++x) img[size_t(y * kW + x)] *= bias;
    t.add_pass(img);
  }
  return t;
}

TEST(PassTileCompare, FalseAlarmRateAtMostAlphaUnderDependentTiles) {
  std::mt19937_64 rng(0x9e3779b97f4a7c15ull);
  constexpr int kPairs = 400;
  constexpr double kAlpha = 0.05;
  int rejected = 0;
  for (int i = 0; i < kPairs; ++i) {
    const PassTiles a = render(rng, 16, 1.0), b = render(rng, 16, 1.0);
    const PassTileCompareResult r = compare_pass_tiles(a, b, kAlpha);
    EXPECT_EQ(r.tested_tiles, 64 * 3);
    EXPECT_EQ(r.tested_totals, 3);
    rejected += r.rejects();
  }
  std::printf("pass-tile test, dependent tiles: %d of %d pairs rejected at alpha %.2f\n", rejected, kPairs, kAlpha);
  // One-sided: the rate must not exceed alpha (Bonferroni is conservative; 0 is fine).
  const double p_upper = stats::binomial_test(rejected, kPairs, kAlpha).p_value;
  EXPECT_FALSE(rejected > kAlpha * kPairs && p_upper < 1e-3) << rejected << " of " << kPairs << " pairs rejected";
}

// Negative control: a 10% bias confined to the bright block must be caught.
TEST(PassTileCompare, TenPercentBiasInOneTileIsCaught) {
  std::mt19937_64 rng(0xd1b54a32d192ed03ull);
  constexpr int kPairs = 200;
  int caught = 0;
  for (int i = 0; i < kPairs; ++i) {
    const PassTileCompareResult r = compare_pass_tiles(render(rng, 32, 1.1), render(rng, 32, 1.0), 0.05);
    caught += r.rejects();
    if (r.rejects()) {
      EXPECT_GE(r.worst_tile, 0);
    }
  }
  std::printf("pass-tile test, 10%% bias in one tile: caught in %d of %d pairs\n", caught, kPairs);
  EXPECT_GE(caught, 0.9 * kPairs) << caught << " of " << kPairs;
}

TEST(PassTileCompare, TilesSumTheirPixelsAndRoundTripThroughJson) {
  PassTiles t(5, 3, 8, 8);  // the grid shrinks to the image: 5 x 3 tiles of one pixel
  EXPECT_EQ(t.grid_x(), 5);
  EXPECT_EQ(t.grid_y(), 3);
  std::vector<Rgb> pass(15);
  for (int i = 0; i < 15; ++i) pass[size_t(i)] = Rgb(i, 2 * i, 0.5);
  t.add_pass(pass);
  t.add_pass(pass);
  PassTiles big(17, 9, 4, 2);
  std::vector<Rgb> ones(17 * 9, Rgb(1.0));
  big.add_pass(ones);
  double total = 0.0;
  for (int k = 0; k < big.tiles(); ++k) total += big.sum(0, k)[0];
  EXPECT_DOUBLE_EQ(total, 17.0 * 9.0);
  const std::string path = ::testing::TempDir() + "pass_tiles_roundtrip.json";
  {
    FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    const std::string s = t.to_json();
    std::fwrite(s.data(), 1, s.size(), f);
    std::fclose(f);
  }
  const PassTiles back = PassTiles::read(path);
  ASSERT_EQ(back.passes(), 2);
  for (int k = 0; k < 15; ++k) EXPECT_EQ(back.sum(1, k), t.sum(1, k));
  EXPECT_THROW(compare_pass_tiles(t, big, 0.01), std::invalid_argument);
  EXPECT_THROW(PassTiles::read(path + ".missing"), std::runtime_error);
}

}  // namespace
}  // namespace tb

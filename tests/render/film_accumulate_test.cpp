// Film accumulation: filters, Welch samples, NaN/Inf rejection with reproducer, and
// bit-identical results for 1 and 2 threads with tiles and splat buffers.
#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/film/film_parallel.h"
#include "lib/film/filter.h"

namespace tb {
namespace {

TEST(FilmAccumulate, BoxFilterAveragesSamplesInThePixel) {
  Film film(4, 3);
  film.add_sample({1.25, 2.5}, Rgb(1, 2, 3), 0);
  film.add_sample({1.75, 2.0}, Rgb(3, 2, 1), 1);
  film.add_sample({2.0, 2.0}, Rgb(5, 5, 5), 2);  // on the edge: belongs to pixel 2 only
  film.end_pass();
  EXPECT_EQ(film.pixel(1, 2), Rgb(2, 2, 2));
  EXPECT_EQ(film.pixel(2, 2), Rgb(5, 5, 5));
  EXPECT_EQ(film.pixel(0, 0), Rgb(0, 0, 0));
  EXPECT_EQ(film.empty_pixel_passes(), 10);
}

TEST(FilmAccumulate, GaussianFilterWeights) {
  const GaussianFilter g(Vec2(1.5), 0.5);
  EXPECT_GT(g.eval({0, 0}), g.eval({0.5, 0}));
  EXPECT_EQ(g.eval({1.5, 0}), 0.0);
  EXPECT_NEAR(g.eval({0.3, -0.2}), g.eval({-0.3, 0.2}), 1e-15);
  // A constant signal stays constant under any filter (weights are normalised per pixel).
  Film film(8, 8, std::make_shared<GaussianFilter>(Vec2(1.5), 0.5));
  Rng rng(3);
  for (int i = 0; i < 20000; ++i) film.add_sample({rng.uniform() * 8, rng.uniform() * 8}, Rgb(0.7), uint64_t(i));
  film.end_pass();
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_NEAR(film.pixel(x, y).g, 0.7, 1e-12);
}

TEST(FilmAccumulate, WelchSamplesArePassAverages) {
  Film film(1, 1);
  const double passes[3][2] = {{1, 3}, {2, 2}, {0, 8}};  // pass means 2, 2, 4
  for (const auto& p : passes) {
    film.add_sample({0.5, 0.5}, Rgb(p[0]), 0);
    film.add_sample({0.5, 0.5}, Rgb(p[1]), 1);
    film.end_pass();
  }
  const WelchImage& w = film.welch();
  EXPECT_EQ(w.count[0], 3);
  EXPECT_DOUBLE_EQ(w.mean(0).r, 8.0 / 3.0);
  // Sample variance of {2, 2, 4}: mean 8/3, sum of squared deviations 8/3, / 2.
  EXPECT_NEAR(w.variance(0).r, 4.0 / 3.0, 1e-12);
}

TEST(FilmAccumulate, SplatsScaledAtEndOfPass) {
  Film film(2, 2);
  film.splat({0.5, 1.5}, Rgb(1.0), 0);
  film.splat({0.7, 1.2}, Rgb(2.0), 1);
  film.splat({-1.0, 0.0}, Rgb(1.0), 2);  // outside: dropped and counted
  film.end_pass(0.5);
  EXPECT_EQ(film.pixel(0, 1), Rgb(1.5));
  EXPECT_EQ(film.splats_outside(), 1);
  film.splat({0.5, 0.5}, Rgb(1.0), 3);
  EXPECT_THROW(film.end_pass(), std::logic_error);  // splats would be dropped silently
}

TEST(FilmAccumulate, NonFiniteSamplesAreCountedWithReproducer) {
  Film film(4, 4);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(film.add_sample({2.5, 1.5}, Rgb(nan, 0, 0), 42));
  EXPECT_FALSE(film.add_sample({nan, 1.5}, Rgb(1.0), 43));
  EXPECT_FALSE(film.splat({3.5, 3.5}, Rgb(0, kInfinity, 0), 44));
  EXPECT_TRUE(film.add_sample({2.5, 1.5}, Rgb(1.0), 45));
  film.end_pass();
  EXPECT_EQ(film.nonfinite().count(), 3);
  const auto& k = film.nonfinite().kept();
  ASSERT_EQ(k.size(), 3u);
  EXPECT_EQ(k[0].pixel_x, 2);
  EXPECT_EQ(k[0].pixel_y, 1);
  EXPECT_EQ(k[0].sample_index, 42u);
  EXPECT_EQ(k[1].pixel_x, -1);
  EXPECT_TRUE(k[2].splat);
  EXPECT_EQ(film.pixel(2, 1), Rgb(1.0));  // the NaN did not enter
  EXPECT_NE(film.nonfinite().summary().find("sample 42"), std::string::npos);
}

TEST(FilmAccumulate, FarAwaySamplesDoNotOverflow) {
  Film film(4, 4, std::make_shared<GaussianFilter>(Vec2(1.5), 0.5));
  EXPECT_TRUE(film.add_sample({1e300, -1e300}, Rgb(1.0), 0));
  EXPECT_TRUE(film.add_sample({-0.5, 2.0}, Rgb(1.0), 1));  // within the radius of pixel 0
  film.end_pass();
  EXPECT_EQ(film.pixel(0, 2), Rgb(1.0));
  EXPECT_EQ(film.pixel(3, 3), Rgb(0.0));
}

Film render_parallel(size_t threads, uint64_t seed) {
  ThreadLimit limit(threads);
  Film film(37, 23, std::make_shared<GaussianFilter>(Vec2(1.5), 0.5));
  for (int pass = 0; pass < 2; ++pass) {
    for_each_film_tile(film, 8, [&](FilmTile& tile) {
      const PixelBounds& b = tile.pixels();
      for (int y = b.y0; y < b.y1; ++y)
        for (int x = b.x0; x < b.x1; ++x)
          for (uint64_t s = 0; s < 4; ++s) {
            const uint64_t idx = (uint64_t(y) * 37 + uint64_t(x)) * 4 + s;
            Rng rng = Rng::for_sample(seed, uint64_t(pass), idx);
            const Vec2 u = rng.uniform2();
            tile.add_sample({x + u.x, y + u.y}, Rgb(rng.uniform(), rng.uniform(), 1.0), idx);
          }
    });
    splat_parallel(film, 20000, 256, [&](uint64_t s, SplatBuffer& buf) {
      Rng rng = Rng::for_sample(seed, 100 + uint64_t(pass), s);
      buf.splat({rng.uniform() * 37, rng.uniform() * 23}, Rgb(rng.uniform()), s);
    });
    film.end_pass(37.0 * 23.0 / 20000.0);
  }
  return film;
}

TEST(FilmAccumulate, BitIdenticalForOneAndTwoThreads) {
  const Film a = render_parallel(1, 5), b = render_parallel(2, 5);
  for (size_t i = 0; i < a.welch().pixels(); ++i) {
    EXPECT_EQ(a.welch().sum[i], b.welch().sum[i]) << i;
    EXPECT_EQ(a.welch().sum_sq[i], b.welch().sum_sq[i]) << i;
  }
}

// The same weights as BoxFilter(0.5), but not a BoxFilter: FilmTile takes its general loop.
class LoopBoxFilter final : public Filter {
 public:
  std::string_view name() const override { return "loop-box"; }
  Vec2 radius() const override { return Vec2(0.5); }
  double eval(const Vec2& d) const override { return BoxFilter(Vec2(0.5)).eval(d); }
};

// FilmTile's one-pixel path for BoxFilter(0.5) against the general footprint loop: integer,
// half-integer, tiny, negative, out-of-tile and far positions; sums equal bit for bit.
TEST(FilmAccumulate, UnitBoxFastPathEqualsFilterLoop) {
  const PixelBounds px{3, 2, 11, 9}, store{2, 1, 12, 10};
  FilmTile fast(px, store, std::make_shared<BoxFilter>()), loop(px, store, std::make_shared<LoopBoxFilter>());
  std::vector<Vec2> pos = {{3.0, 2.0},  {4.5, 5.5},    {11.0, 9.0},     {2.0, 1.0},  {12.0, 10.0}, {1e-300, 3.2},
                           {-0.0, 4.0}, {-1e-17, 4.0}, {7.999999, 3.0}, {1e30, 5.0}, {5.0, -3.5}};
  Rng rng(3);
  for (int k = 0; k < 20000; ++k) pos.emplace_back(rng.uniform() * 14.0 - 1.0, rng.uniform() * 12.0 - 1.0);
  uint64_t index = 0;
  for (const Vec2& p : pos) {
    const Rgb L(rng.uniform(), rng.uniform() * 100.0, 1.0 / (1e-3 + rng.uniform()));
    EXPECT_EQ(fast.add_sample(p, L, index), loop.add_sample(p, L, index));
    ++index;
  }
  for (int y = store.y0; y < store.y1; ++y)
    for (int x = store.x0; x < store.x1; ++x) {
      EXPECT_EQ(fast.weighted_sum(x, y), loop.weighted_sum(x, y)) << x << "," << y;
      EXPECT_EQ(fast.weight_sum(x, y), loop.weight_sum(x, y)) << x << "," << y;
    }
}

// Film::merge_tiles (bands of rows in parallel) against merge_tile one tile after another, with a
// Gaussian filter so that the tiles' footprints overlap: the sums must agree bit for bit.
TEST(FilmAccumulate, ParallelTileMergeEqualsSequential) {
  const auto filter = std::make_shared<GaussianFilter>(Vec2(1.5, 1.5), 0.5);
  Film seq(37, 29, filter), par(37, 29, filter);
  std::vector<FilmTile> tiles;
  for (int j = 0; j < 29; j += 8)
    for (int i = 0; i < 37; i += 8) tiles.push_back(seq.make_tile({i, j, std::min(37, i + 8), std::min(29, j + 8)}));
  Rng rng(7);
  uint64_t index = 0;
  for (FilmTile& t : tiles)
    for (int k = 0; k < 200; ++k) {
      const PixelBounds& p = t.pixels();
      const Vec2 raster(p.x0 + rng.uniform() * p.width(), p.y0 + rng.uniform() * (p.y1 - p.y0));
      t.add_sample(raster, Rgb(rng.uniform(), rng.uniform() * 1e3, rng.uniform() * 1e-3), index++);
    }
  for (const FilmTile& t : tiles) seq.merge_tile(t);
  {
    ThreadLimit limit(2);
    par.merge_tiles(tiles);
  }
  seq.end_pass();
  par.end_pass();
  for (size_t i = 0; i < seq.welch().pixels(); ++i) EXPECT_EQ(seq.welch().sum[i], par.welch().sum[i]) << i;
  EXPECT_EQ(seq.empty_pixel_passes(), par.empty_pixel_passes());
}

}  // namespace
}  // namespace tb

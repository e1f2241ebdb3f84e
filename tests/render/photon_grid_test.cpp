// The photon map's spatial index (PointGrid, lib/integrator/photon_map.h): a range query returns
// exactly the points within r (|p - x|^2 <= r^2), each once, compared with brute force; with the
// default table, with a tiny table where different cells share buckets, for radii below, at and
// above the cell size, and for points on cell boundaries. And pm / sppm renders are identical for
// 1 and 2 threads.
#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/integrator/photon_map.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

std::vector<uint32_t> brute_force(const std::vector<Vec3>& pts, const Vec3& x, double r) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < pts.size(); ++i) {
    const Vec3 d = pts[i] - x;
    if (d.x * d.x + d.y * d.y + d.z * d.z <= r * r) out.push_back(static_cast<uint32_t>(i));
  }
  return out;
}

std::vector<uint32_t> query(const PointGrid& g, const Vec3& x, double r) {
  std::vector<uint32_t> out;
  g.for_each_within(x, r, [&](uint32_t i) { out.push_back(i); });
  std::sort(out.begin(), out.end());
  return out;
}

// Points clustered on a few planes (as photons are) plus uniform ones, some exactly on cell edges.
std::vector<Vec3> make_points(Rng& rng, size_t n, double cell) {
  std::vector<Vec3> pts;
  for (size_t i = 0; i < n; ++i) {
    const double a = rng.uniform() * 2 - 1, b = rng.uniform() * 2 - 1, c = rng.uniform() * 2 - 1;
    switch (i % 4) {
      case 0: pts.emplace_back(a, b, 0.25); break;
      case 1: pts.emplace_back(a, -1.0, c); break;
      case 2: pts.emplace_back(std::round(a / cell) * cell, std::round(b / cell) * cell, c); break;
      default: pts.emplace_back(a, b, c); break;
    }
  }
  return pts;
}

void expect_exact(const PointGrid& g, const std::vector<Vec3>& pts, Rng& rng, double cell) {
  for (int q = 0; q < 400; ++q) {
    const double r = cell * (q % 4 == 0 ? 0.3 : q % 4 == 1 ? 1.0 : q % 4 == 2 ? 0.999 : 2.5);
    // Queries at points (distance 0 and neighbours at exactly r are likely), on the planes and anywhere.
    Vec3 x = q % 3 == 0 ? pts[rng.uniform_below(static_cast<uint32_t>(pts.size()))]
                        : Vec3(rng.uniform() * 2.2 - 1.1, rng.uniform() * 2.2 - 1.1, q % 3 == 1 ? 0.25 : rng.uniform() * 2 - 1);
    const auto got = query(g, x, r);
    const auto want = brute_force(pts, x, r);
    ASSERT_EQ(got, want) << "query " << q << " r " << r;  // sorted: also no point reported twice
  }
}

TEST(PhotonGrid, RangeQueriesMatchBruteForce) {
  Rng rng = Rng::for_sample(3, 0x6772, 0);
  for (const double cell : {0.05, 0.1, 0.37}) {
    const auto pts = make_points(rng, 5000, cell);
    PointGrid g;
    g.build(pts, cell);
    EXPECT_EQ(g.size(), pts.size());
    expect_exact(g, pts, rng, cell);
  }
}

TEST(PhotonGrid, CollidingBucketsAreVisitedOnce) {
  Rng rng = Rng::for_sample(4, 0x6772, 0);
  const double cell = 0.1;
  const auto pts = make_points(rng, 3000, cell);
  for (const size_t buckets : {size_t{1}, size_t{4}, size_t{32}}) {
    PointGrid g;
    g.build_with_buckets(pts, cell, buckets);
    expect_exact(g, pts, rng, cell);
  }
}

TEST(PhotonGrid, ExactDistanceIsInsideAndBoundaryPoints) {
  // Points at exactly distance r on the axes (representable), and one just outside.
  const std::vector<Vec3> pts = {Vec3(0.5, 0, 0), Vec3(0, -0.5, 0), Vec3(0, 0, 0.5), Vec3(0.5000001, 0, 0),
                                 Vec3(0, 0, 0), Vec3(-0.25, 0.25, 0)};
  PointGrid g;
  g.build(pts, 0.5);
  EXPECT_EQ(query(g, Vec3(0.0), 0.5), (std::vector<uint32_t>{0, 1, 2, 4, 5}));
  EXPECT_EQ(query(g, Vec3(0.0), 0.0), (std::vector<uint32_t>{4}));
  PointGrid empty;
  empty.build(std::vector<Vec3>{}, 1.0);
  EXPECT_TRUE(query(empty, Vec3(0.0), 1.0).empty());
  EXPECT_THROW(g.build(pts, 0.0), std::invalid_argument);
}

TEST(PhotonMapping, ImagesIdenticalForOneAndTwoThreads) {
  const auto world = load_scene_at_resolution("cornell-box.json", 12, 12);
  for (const char* name : {"pm", "sppm"}) {
    const IntegratorInfo* integ = find_integrator(name);
    ASSERT_NE(integ, nullptr) << name;
    RenderSettings st;
    st.spp = 8;
    st.passes = 2;
    st.seed = 9;
    st.params = {{"radius", 0.05}, {"photons", 20000}};
    std::vector<Rgb> img[2];
    for (int t = 0; t < 2; ++t) {
      const ThreadLimit limit(static_cast<size_t>(t + 1));
      Film film(world->camera().width(), world->camera().height());
      EXPECT_EQ(integ->render(*world, st, film), 2);
      img[t] = film.mean_image();
    }
    ASSERT_EQ(img[0].size(), img[1].size());
    double sum = 0;
    for (size_t i = 0; i < img[0].size(); ++i) {
      EXPECT_EQ(img[0][i].r, img[1][i].r) << name << " pixel " << i;
      EXPECT_EQ(img[0][i].g, img[1][i].g) << name << " pixel " << i;
      EXPECT_EQ(img[0][i].b, img[1][i].b) << name << " pixel " << i;
      sum += img[0][i].r + img[0][i].g + img[0][i].b;
    }
    EXPECT_GT(sum, 0.0) << name;
  }
}

}  // namespace
}  // namespace tb

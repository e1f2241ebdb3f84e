// Pieces of mlt-stratified (lib/mcmc/path_space/stratified_mlt.h): the target W~ of Zirr &
// Dachsbacher 2020's Eq. 8 (footnote form) on BDPT-sampled paths, r~ of Eq. 21 read from the
// camera, the start-up term's density identity, and the determinism of the pilot and of the
// render for any thread count. The image-level unbiasedness is checked by tb check
// render.mlt_stratified.* (validate/checks/mcmc_path_space_checks.cpp).
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/mcmc/path_space/stratified_mlt.h"
#include "lib/path/light_sampler.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {
namespace {

struct Scene {
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
  explicit Scene(const char* file, int res = 8) {
    setenv("TB_SCENES_DIR", TB_SOURCE_DIR "/scenes", 0);
    world = load_scene_at_resolution(file, res, res);
    lights = std::make_unique<LightSampler>(*world);
    ctx = PathContext{world.get(), lights.get()};
  }
};

// Every connection of n BDPT samples (uniform raster positions) with a positive weighted value:
// calls visit(path, connection, s).
template <class F>
void for_connections(const PathContext& ctx, int n, int max_depth, uint64_t key, F&& visit) {
  const Camera& cam = ctx.world->camera();
  std::vector<PathVertex> cp, lp;
  for (int i = 0; i < n; ++i) {
    Rng stream = Rng::for_sample(7, key, static_cast<uint64_t>(i));
    RngUniforms u(stream);
    const Vec2 uf = u.next2(), lens_u = u.next2();
    const int nc = generate_camera_subpath(ctx, Vec2(uf.x * cam.width(), uf.y * cam.height()), lens_u, u,
                                           max_depth + 2, &cp);
    const int nl = generate_light_subpath(ctx, u, max_depth + 1, &lp);
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t < 2 || s + t - 2 > max_depth) continue;
        const Connection c = connect_bdpt(ctx, lp, cp, s, t, u);
        if (luminance(c.value) > 0.0) visit(assemble_connection(lp, cp, s, t, c), c, s);
      }
  }
}

class StratifiedMltScenes : public ::testing::TestWithParam<std::string> {};

// On sampled paths: W~ = min{ r~ p, Y(f) / B } (so W~ <= both), r~ >= 1, W~ > 0 where f > 0,
// r~ with the Sec. 6.6 reduction <= r~ without; and BDPT's unweighted value equals f / p_{s,t}
// with f and p_{s,t} of the path-space convention (the identity the start-up term
// Y(c.value) W~ / Y(f) = w_{s,t} W~ / p_{s,t} rests on).
TEST_P(StratifiedMltScenes, TargetBoundsOnSampledPaths) {
  const Scene sc(GetParam().c_str());
  const int max_depth = 6;
  const PathTarget plain{&sc.ctx};
  int paths = 0, capped = 0, bounded = 0, infinite = 0, density_checked = 0;
  // B from far below to far above the scenes' pixel values: both branches of the min occur.
  for (const double B : {1e-4, 0.1, 30.0}) {
    const StratifiedPathTarget with(sc.ctx, B, true), without(sc.ctx, B, false);
    for_connections(sc.ctx, 400, max_depth, 0x5157ULL, [&](const MltPath& x, const Connection& c, int s) {
      const Rgb f = plain.contribution(x);
      const double y = luminance(f);
      if (!(y > 0.0)) return;
      ++paths;
      const double r = with.ratio(x), r_all = without.ratio(x), p = with.technique_sum(x), w = with(x, f);
      ASSERT_GE(r, 1.0);
      ASSERT_GE(r_all, r * (1.0 - 1e-12));
      ASSERT_GT(p, 0.0) << "a BDPT-sampled path has a technique of positive density";
      ASSERT_GT(w, 0.0);
      ASSERT_LE(w, y / B * (1.0 + 1e-12));
      if (std::isinf(r)) {
        ++infinite;
        ASSERT_DOUBLE_EQ(w, y / B);
      } else {
        ASSERT_LE(w, r * p * (1.0 + 1e-12));
        ASSERT_NEAR(w, std::min(r * p, y / B), 1e-12 * w);
        (w < y / B ? bounded : capped) += 1;
      }
      // The start-up term's identity: Y(unweighted) = Y(f) / p_{s,t}.
      const double ps = technique_density(path_densities(sc.ctx, x.v, DiracPolicy::kCoefficient), s);
      if (ps > 0.0) {
        ++density_checked;
        EXPECT_NEAR(luminance(c.unweighted) * ps, y, 1e-6 * y) << "s = " << s << ", k = " << x.segments();
      }
    });
  }
  EXPECT_GT(paths, 300);
  EXPECT_GT(density_checked, paths / 2);
  EXPECT_GT(capped, 0);
  EXPECT_GT(bounded, 0);
  RecordProperty("paths", paths);
  RecordProperty("bounded", bounded);
  RecordProperty("capped", capped);
  RecordProperty("infinite_ratio", infinite);
}

INSTANTIATE_TEST_SUITE_P(Scenes, StratifiedMltScenes, ::testing::Values("cornell-box.json", "caustic.json", "glossy.json"),
                         [](const auto& info) {
                           std::string n = info.param.substr(0, info.param.find('.'));
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

// A path seen directly (x_0 on the emitter, x_1 the lens): r~ = 1 and W~ = min{p, Y / B}.
TEST(StratifiedMlt, DirectlySeenEmitterHasRatioOne) {
  const Scene sc("cornell-box.json");
  const StratifiedPathTarget w(sc.ctx, 1.0, true);
  int seen = 0;
  for_connections(sc.ctx, 400, 3, 0x5158ULL, [&](const MltPath& x, const Connection&, int) {
    if (x.segments() != 1) return;
    ++seen;
    EXPECT_EQ(w.ratio(x), 1.0);
  });
  EXPECT_GT(seen, 0);
}

// The pilot's B: the same bits for 1, 2 and 4 threads, and close to the BDPT image's mean pixel.
TEST(StratifiedMlt, PilotDeterministicForAnyThreadCount) {
  const Scene sc("cornell-box.json");
  auto pilot = [&](size_t threads) {
    ThreadLimit limit(threads);
    return stratified_pilot_brightness(sc.ctx, 11, 3000, 3);
  };
  const double b1 = pilot(1), b2 = pilot(2), b4 = pilot(4);
  EXPECT_GT(b1, 0.0);
  EXPECT_EQ(b1, b2);
  EXPECT_EQ(b1, b4);
  // Another seed: a different stream (independent of the chains' bootstrap keys as well).
  EXPECT_NE(b1, stratified_pilot_brightness(sc.ctx, 12, 3000, 3));
}

// The render: bit-identical for 1 and 2 threads; the reported B is the pilot's.
TEST(StratifiedMlt, RenderDeterministicForAnyThreadCount) {
  const Scene sc("cornell-box.json");
  RenderSettings st;
  st.spp = 64;
  st.passes = 5;
  st.max_depth = 3;
  st.seed = 3;
  MltStats s1;
  auto run = [&](size_t threads) {
    ThreadLimit limit(threads);
    Film film(8, 8);
    s1 = run_mlt_stratified(*sc.world, st, film);
    return film.welch().sum;
  };
  const auto a = run(1), b = run(2);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "pixel " << i;
  EXPECT_EQ(s1.chains, 5);
  EXPECT_GT(s1.brightness, 0.0);
  EXPECT_EQ(s1.pilot_samples, 1024);
  EXPECT_EQ(s1.brightness, stratified_pilot_brightness(sc.ctx, 3, 1024, 3));
  // b~ = int W~ dmu <= int Y(f) / B dmu = 1 (Eq. 8: W~ <= Y(f) / B); the chains' mean estimates it.
  EXPECT_GT(s1.b_mean, 0.0);
  EXPECT_LT(s1.b_mean, 1.5);
}

}  // namespace
}  // namespace tb::path_space

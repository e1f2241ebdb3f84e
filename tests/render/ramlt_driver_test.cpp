// Regional adaptive MLT (lib/mcmc/path_space/ramlt*.h, docs/ramlt.md): the direction kernel's
// normalisation (Otsu Sec. 3), the screen partition (Otsu Sec. 5.4), the registry entries, and the
// driver's synchronous adaptation: bit-identical images and lambda maps for 1 and 2 threads.
#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>

#include "lib/core/parallel.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/ramlt_adaptation.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/mcmc/path_space/ramlt_direction.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {
namespace {

std::unique_ptr<World> cornell(int res) {
  setenv("TB_SCENES_DIR", TB_SOURCE_DIR "/scenes", 0);
  return load_scene_at_resolution("cornell-box.json", res, res);
}

TEST(RamltDirection, ErfInverseInvertsErf) {
  for (double v : {-0.999999, -0.9, -0.3, 0.0, 1e-9, 0.2, 0.7, 0.99, 0.9999999})
    EXPECT_NEAR(std::erf(erf_inverse(v)), v, 1e-14 * std::max(1.0, 1.0 / (1.0 - std::abs(v)))) << v;
}

TEST(RamltDirection, AngleDensityIntegratesToOne) {
  for (double sigma : {0.01, 0.3, 1.0, 3.0, 20.0}) {
    const int n = 200000;
    const double h = kPi / n;
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += TruncatedNormalDirection::angle_density((i + 0.5) * h, sigma) * h;
    EXPECT_NEAR(s, 1.0, 1e-6) << sigma;
  }
}

TEST(RamltDirection, SampledAngleMatchesInverseCdf) {
  // t = sample_angle(u) satisfies erf(t / (sigma sqrt 2)) = u Z(sigma).
  for (double sigma : {0.02, 0.5, 2.5})
    for (double u : {0.01, 0.25, 0.5, 0.9, 0.999}) {
      const double t = TruncatedNormalDirection::sample_angle(u, sigma);
      EXPECT_NEAR(std::erf(t / (sigma * std::sqrt(2.0))), u * TruncatedNormalDirection::mass(sigma), 1e-12);
    }
}

TEST(RamltPartition, GridRegionsFollowPixels) {
  const auto world = cornell(16);
  const LightSampler lights(*world);
  const PathContext ctx{world.get(), &lights};
  const auto grid = ScreenPartition::make(ctx, "grid", 4);
  EXPECT_EQ(grid->regions(), 16);
  EXPECT_TRUE(grid->adapts());
  EXPECT_EQ(ScreenPartition::make(ctx, "fixed")->regions(), 1);
  EXPECT_FALSE(ScreenPartition::make(ctx, "fixed")->adapts());
  EXPECT_TRUE(ScreenPartition::make(ctx, "global")->adapts());
  // A path's region is the cell of its raster position, x fastest (partition.h).
  Rng rng = Rng::for_sample(3, 0, 0);
  RngUniforms u(rng);
  int checked = 0;
  for (int i = 0; i < 200; ++i) {
    const auto x = sample_bdpt_path(ctx, u, 3);
    if (!x) continue;
    const auto r = path_raster(ctx, *x);
    if (!r) continue;
    const int ix = static_cast<int>(r->x / 4.0), iy = static_cast<int>(r->y / 4.0);
    EXPECT_EQ(grid->region_of(*x), std::min(ix, 3) + 4 * std::min(iy, 3));
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(RamltQuadtree, SplitKeepsIndicesAndRefinesTheLeaf) {
  mcmc::QuadtreePartition q({0.0, 0.0}, {1.0, 1.0}, 3);
  EXPECT_EQ(q.regions(), 1);
  EXPECT_EQ(q.region_of({0.7, 0.2}), 0);
  EXPECT_EQ(q.split(0), 1);
  ASSERT_EQ(q.regions(), 4);
  EXPECT_EQ(q.region_of({0.2, 0.2}), 0);  // lower x, lower y keeps the parent's index
  EXPECT_EQ(q.region_of({0.7, 0.2}), 1);
  EXPECT_EQ(q.region_of({0.2, 0.7}), 2);
  EXPECT_EQ(q.region_of({0.7, 0.7}), 3);
  EXPECT_EQ(q.region_of({1.5, -3.0}), 1);  // outside: nearest boundary leaf
  EXPECT_EQ(q.split(3), 4);                // leaf 3 -> 3, 4, 5, 6
  EXPECT_EQ(q.region_of({0.6, 0.6}), 3);
  EXPECT_EQ(q.region_of({0.9, 0.9}), 6);
  EXPECT_EQ(q.region_of({0.2, 0.2}), 0);
  EXPECT_EQ(q.depth(6), 2);
  EXPECT_EQ(q.lo(6)[0], 0.75);
  EXPECT_EQ(q.split(6), 7);
  EXPECT_EQ(q.split(7), -1);  // max depth 3
}

TEST(RamltAdaptation, SplittableEqualsRegionalAdaptationWithoutSplits) {
  mcmc::AdaptationOptions o;
  mcmc::OtsuAdaptation a(3, o);
  SplittableAdaptation<> b(3, o);
  Rng rng = Rng::for_sample(11, 0, 0);
  for (int i = 0; i < 3000; ++i) {
    const int r = static_cast<int>(rng.uniform() * 3.0);
    const double acc = rng.uniform();
    a.observe(r, acc);
    b.observe(r, acc);
  }
  for (int r = 0; r < 3; ++r) {
    EXPECT_EQ(a.lambda(r), b.lambda(r));
    EXPECT_EQ(a.updates(r), b.updates(r));
  }
  // A split (Otsu Sec. 6.2): children start from the parent's lambda and n_k / 4 updates.
  const double l1 = b.lambda(1);
  const int n1 = b.updates(1);
  b.split(1, 3);
  ASSERT_EQ(b.regions(), 6);
  for (int r : {1, 3, 4, 5}) {
    EXPECT_EQ(b.lambda(r), l1);
    EXPECT_EQ(b.updates(r), n1 / 4);
  }
}

TEST(RamltRegistry, RegisteredOutsideTheDefaultMixture) {
  const auto world = cornell(8);
  const LightSampler lights(*world);
  const PathContext ctx{world.get(), &lights};
  const PathMutationSettings s;
  ASSERT_NE(find_path_mutation("ramlt-lens"), nullptr);
  ASSERT_NE(find_path_mutation("ramlt-multichain"), nullptr);
  EXPECT_FALSE(find_path_mutation("ramlt-lens")->in_default_mixture);
  for (const auto& m : make_path_mutations(ctx, s)) EXPECT_EQ(m->name().rfind("ramlt-", 0), std::string::npos);
  EXPECT_EQ(make_all_path_mutations(ctx, s).size(), path_mutations().size());
}

TEST(RamltRegistry, ParametersByName) {
  const RamltOptions o = apply_ramlt_params({}, {{"grid", 8}, {"refine_every", 1000}, {"split_threshold", 50},
                                                 {"lambda0", -2}, {"target_acceptance", 0.3}, {"batch_steps", 4}});
  EXPECT_EQ(o.grid, 8);
  EXPECT_EQ(o.refine_every, 1000);
  EXPECT_EQ(o.split_threshold, 50);
  EXPECT_EQ(o.adaptation.lambda0, -2.0);
  EXPECT_EQ(o.adaptation.target_acceptance, 0.3);
  EXPECT_EQ(o.batch_steps, 4);
  EXPECT_THROW(apply_ramlt_params({}, {{"grid", 0}}), std::invalid_argument);
  EXPECT_THROW(apply_ramlt_params({}, {{"target_acceptance", 1.0}}), std::invalid_argument);
  for (const char* name : {"ramlt-lens", "ramlt-multichain"}) {
    const IntegratorInfo* info = find_integrator(name);
    ASSERT_NE(info, nullptr) << name;
    EXPECT_EQ(validate_params(*info, {{"grid", 8}, {"split_threshold", 10}}), "");
    EXPECT_NE(validate_params(*info, {{"chains", 8}}), "");
  }
}

RamltStats render(const World& w, Film& f, const RamltOptions& o) {
  RenderSettings st;
  st.passes = 8;
  st.spp = 8 * 32;
  st.max_depth = 3;
  st.seed = 7;
  return run_ramlt(w, st, f, o);
}

TEST(RamltDriver, BitIdenticalForAnyThreadCount) {
  const auto world = cornell(8);
  RamltOptions o;
  o.grid = 4;
  Film f1(8, 8), f2(8, 8);
  RamltStats s1, s2;
  {
    const ThreadLimit one(1);
    s1 = render(*world, f1, o);
  }
  {
    const ThreadLimit two(2);
    s2 = render(*world, f2, o);
  }
  const auto a = f1.mean_image(), b = f2.mean_image();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
  EXPECT_EQ(s1.maps.lambda, s2.maps.lambda);
  EXPECT_EQ(s1.maps.visits, s2.maps.visits);
  EXPECT_EQ(s1.maps.acceptance_sum, s2.maps.acceptance_sum);
  // The adaptation ran: lambda moved away from lambda0 in some region.
  int moved = 0;
  for (double l : s1.maps.lambda) moved += l != o.adaptation.lambda0;
  EXPECT_GT(moved, 0);
  EXPECT_GT(s1.batches, 1);
}

TEST(RamltDriver, QuadtreeRefinesAndStaysBitIdentical) {
  const auto world = cornell(8);
  RamltOptions o;
  o.partition = "quadtree";
  o.refine_every = 2048;  // small: several refinements in a test-sized run
  o.split_threshold = 100;
  Film f1(8, 8), f2(8, 8);
  RamltStats s1, s2;
  {
    const ThreadLimit one(1);
    s1 = render(*world, f1, o);
  }
  {
    const ThreadLimit two(2);
    s2 = render(*world, f2, o);
  }
  EXPECT_GT(s1.maps.refinements, 1);
  // Every chain ran exactly M = spp P / chains steps although the batch length grew with the tree.
  EXPECT_EQ(s1.mlt.mutations_total, 8 * (8 * 32 * 64 / 8));
  int64_t proposed = 0;
  for (const auto& m : s1.mlt.mutations) proposed += m.proposed;
  EXPECT_EQ(proposed, s1.mlt.mutations_total);
  EXPECT_GT(s1.maps.regions, 4);
  EXPECT_EQ(s1.maps.leaf_boxes.size(), static_cast<size_t>(s1.maps.regions));
  EXPECT_EQ(s1.maps.lambda, s2.maps.lambda);
  const auto a = f1.mean_image(), b = f2.mean_image();
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
  // The leaves tile [0, 1]^2.
  double area = 0.0;
  for (const auto& bx : s1.maps.leaf_boxes) area += (bx[2] - bx[0]) * (bx[3] - bx[1]);
  EXPECT_NEAR(area, 1.0, 1e-12);
}

TEST(RamltDriver, FixedPartitionDoesNotAdapt) {
  const auto world = cornell(8);
  RamltOptions o;
  o.partition = "fixed";
  Film f(8, 8);
  const RamltStats s = render(*world, f, o);
  ASSERT_EQ(s.maps.regions, 1);
  EXPECT_EQ(s.maps.lambda[0], o.adaptation.lambda0);
  EXPECT_EQ(s.maps.updates[0], 0);
  EXPECT_GT(s.maps.visits[0], 0);
}

TEST(RamltPartition4d, GridQuadtreeSplitsOneCellsTree) {
  mcmc::GridQuadtreePartition p({0, 0, 0, 0}, {1, 1, 1, 1}, 2);
  ASSERT_EQ(p.regions(), 4);  // one root per screen cell
  EXPECT_EQ(p.region_of({0.7, 0.2, 0.9, 0.9}), 1);
  EXPECT_EQ(p.region_of({0.2, 0.7, 0.1, 0.1}), 2);
  EXPECT_EQ(p.split(1), 4);  // cell 1's root: 1 keeps the lower-left quadrant, 4..6 appended
  ASSERT_EQ(p.regions(), 7);
  EXPECT_EQ(p.region_of({0.7, 0.2, 0.1, 0.1}), 1);
  EXPECT_EQ(p.region_of({0.7, 0.2, 0.9, 0.1}), 4);
  EXPECT_EQ(p.region_of({0.7, 0.2, 0.1, 0.9}), 5);
  EXPECT_EQ(p.region_of({0.7, 0.2, 0.9, 0.9}), 6);
  EXPECT_EQ(p.region_of({0.2, 0.2, 0.9, 0.9}), 0);  // other cells untouched
  for (int r = 4; r < 7; ++r) EXPECT_EQ(p.cell_of(r), 1);
  const auto g = mcmc::make_partition<4>("grid4d", {{0, 0, 0, 0}, {1, 1, 1, 1}, {2, 2, 3, 3}});
  EXPECT_EQ(g->regions(), 36);
  EXPECT_EQ(g->name(), "grid4d");
  // Dimension 0 fastest: the screen cell is the index modulo 4.
  EXPECT_EQ(g->region_of({0.7, 0.7, 0.5, 0.9}) % 4, 3);
}

TEST(RamltPartition4d, CylindricalIsInTheUnitSquare) {
  for (const Vec3 w : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(-1, 1e-12, 0), Vec3(0, -1, 0)}) {
    const auto c = cylindrical(w);
    EXPECT_GE(c[0], 0.0);
    EXPECT_LE(c[0], 1.0);
    EXPECT_GE(c[1], 0.0);
    EXPECT_LT(c[1], 1.0);
  }
  EXPECT_DOUBLE_EQ(cylindrical(Vec3(0, 0, 1))[0], 1.0);
  EXPECT_DOUBLE_EQ(cylindrical(Vec3(0, -1, 0))[1], 0.75);
}

TEST(RamltDriver, Quadtree4dRefinesAndStaysBitIdentical) {
  setenv("TB_SCENES_DIR", TB_SOURCE_DIR "/scenes", 0);
  const auto world = load_scene_at_resolution("caustic.json", 8, 8);
  RamltOptions o;
  o.perturbation = RamltPerturbation::kMultiChain;
  o.partition = "quadtree4d";
  o.grid = 2;
  o.refine_every = 2048;
  o.split_threshold = 20;
  RenderSettings st;
  st.passes = 8;
  st.spp = 8 * 64;
  st.max_depth = 6;
  st.seed = 3;
  Film f1(8, 8), f2(8, 8);
  RamltStats s1, s2;
  {
    const ThreadLimit one(1);
    s1 = run_ramlt(*world, st, f1, o);
  }
  {
    const ThreadLimit two(2);
    s2 = run_ramlt(*world, st, f2, o);
  }
  EXPECT_EQ(s1.maps.regions, 4);   // sigma_1: the 2 x 2 screen grid
  EXPECT_GT(s1.maps.regions2, 4);  // sigma_2: the direction quadtrees were refined
  EXPECT_GT(s1.maps.refinements, 0);
  EXPECT_EQ(s1.maps.lambda, s2.maps.lambda);
  EXPECT_EQ(s1.maps.lambda2, s2.maps.lambda2);
  const auto a = f1.mean_image(), b = f2.mean_image();
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
  o.perturbation = RamltPerturbation::kLens;  // the 4d partitions are the multi-chain perturbation's
  EXPECT_THROW(run_ramlt(*world, st, f1, o), std::invalid_argument);
}

}  // namespace
}  // namespace tb::path_space

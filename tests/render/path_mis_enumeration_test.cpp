// The independent enumeration of the BDPT techniques that can generate a path
// (validate/render/mis_enumeration.h) on a hand-made path through a mirror, and the MIS invariant
// on sampled paths through Dirac vertices, with its negative control (Dirac flags cleared).
#include "validate/render/mis_enumeration.h"

#include <gtest/gtest.h>

#include "lib/light/infinite_lights.h"
#include "lib/material/lambert.h"
#include "lib/material/smooth_conductor.h"
#include "lib/path/light_sampler.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

// x_0 (area light) - diffuse - mirror - diffuse - lens: techniques s = 0 (hit the light), 1 (next
// event) and 4 (light subpath to the lens) can generate it; s = 2 and 3 would join the mirror.
// With every finite density 1/2 the three have equal densities (three finite factors each, the
// deltas pE[1] and pL[3] generated at the mirror counted as 1): weights 1/3, matching mis_weight.
TEST(MisEnumeration, MirrorPathByHand) {
  const auto world = load_scene_at_resolution("caustic.json", 8, 8);
  const LightSampler sampler(*world);
  const auto choice = sampler.sample(0.5);
  ASSERT_TRUE(choice.has_value());
  ASSERT_TRUE(choice->light->flags() & light_flags::kArea);
  const LambertBsdf diffuse(Rgb(0.5));
  const SmoothConductorBsdf mirror(Rgb(0.2), Rgb(3.0));
  std::vector<PathVertex> x(5);
  x[0].kind = VertexKind::kLight;
  x[0].light = choice->light;
  x[1].bsdf = &diffuse;
  x[2].bsdf = &mirror;
  x[2].delta = true;
  x[3].bsdf = &diffuse;
  x[4].kind = VertexKind::kCamera;
  PathDensities d;
  d.pL.assign(5, 0.5);
  d.pE.assign(5, 0.5);
  d.pL[3] = 0.0;  // generated at the mirror: stored as 0 (lib/path/path.h)
  d.pE[1] = 0.0;
  d.delta = {0, 0, 1, 0, 0};
  const TechniqueEnumeration e = enumerate_techniques(x, d);
  EXPECT_EQ(e.dirac_vertices, 1);
  const std::vector<uint8_t> expected = {1, 1, 0, 0, 1};
  EXPECT_EQ(e.can_generate, expected);
  for (int s = 0; s < 5; ++s) {
    const double want = expected[s] ? 1.0 / 3.0 : 0.0;
    EXPECT_NEAR(e.weight[s], want, 1e-15) << s;
    EXPECT_NEAR(mis_weight(d, s, MisKind::kPower), want, 1e-15) << s;
  }
  // A zero density that is not generated at a Dirac vertex: that technique cannot generate it.
  d.pE[3] = 0.0;  // the lens cannot sample x_3: only s = 4 remains
  const TechniqueEnumeration e2 = enumerate_techniques(x, d);
  EXPECT_EQ(e2.can_generate, (std::vector<uint8_t>{0, 0, 0, 0, 1}));
  EXPECT_DOUBLE_EQ(e2.weight[4], 1.0);
  // The code under test agrees: a real zero is not read as 1 (as pbrt-v3's remap0 would), so the
  // techniques that need pE[3] get weight 0 and the one that remains gets 1, from every s.
  for (int s = 0; s < 5; ++s) EXPECT_DOUBLE_EQ(mis_weight(d, s, MisKind::kPower), s == 4 ? 1.0 : 0.0) << s;
}

// A directional light is an infinite emitter: x_0 is its direction (the delta, pL[0] = its
// selection probability, common to every s >= 1) and pL[1] is the real area density of x_1 on the
// emission disk. Path: direction - diffuse - diffuse - lens; s = 0 is impossible (a direction with
// no extent), s = 1, 2, 3 possible with p_1 = pL0 pE1 pE2, p_2 = pL0 pL1 pE2, p_3 = pL0 pL1 pL2.
TEST(MisEnumeration, DirectionalLightFirstDensityIsReal) {
  const DirectionalLight sun(Vec3(0, -1, 0), Rgb(1.0));
  const LambertBsdf diffuse(Rgb(0.5));
  std::vector<PathVertex> x(4);
  x[0].kind = VertexKind::kLight;
  x[0].light = &sun;
  x[0].infinite = true;
  x[0].delta = true;
  x[1].bsdf = &diffuse;
  x[2].bsdf = &diffuse;
  x[3].kind = VertexKind::kCamera;
  PathDensities d;
  d.pL = {0.5, 0.25, 2.0, 0.0};
  d.pE = {0.7, 1.0, 0.5, 1.0};
  d.delta = {1, 0, 0, 0};
  d.x0_infinite = true;
  const double p1 = 0.5 * 1.0 * 0.5, p2 = 0.5 * 0.25 * 0.5, p3 = 0.5 * 0.25 * 2.0;
  const double sum = p1 * p1 + p2 * p2 + p3 * p3;
  const TechniqueEnumeration e = enumerate_techniques(x, d);
  EXPECT_EQ(e.can_generate, (std::vector<uint8_t>{0, 1, 1, 1}));
  const double want[4] = {0.0, p1 * p1 / sum, p2 * p2 / sum, p3 * p3 / sum};
  for (int s = 0; s < 4; ++s) {
    EXPECT_NEAR(e.weight[s], want[s], 1e-15) << s;
    EXPECT_NEAR(mis_weight(d, s, MisKind::kPower), want[s], 1e-15) << s;
  }
}

TEST(MisEnumeration, InvariantHoldsOnDiracScenesAndControlIsCaught) {
  for (const char* file : {"caustic.json", "dg-mirror-chain.json", "smooth-mesh.json"}) {
    SCOPED_TRACE(file);
    const auto world = load_scene_at_resolution(file, 16, 16);
    MisInvariantOptions o;
    o.subpath_pairs = 500;
    o.seed = 3;
    MisInvariantTally tally;
    double worst_incremental = 0.0;
    sample_mis_invariant(*world, file, o, &tally, &worst_incremental);
    EXPECT_GT(tally.paths, 100);
    EXPECT_TRUE(tally.holds()) << tally.first_violation;
    EXPECT_LT(tally.worst_sum, 1e-12);
    EXPECT_EQ(tally.nonzero_invalid, 0);
    EXPECT_LT(worst_incremental, 1e-9);
    if (std::string(file) != "smooth-mesh.json") {
      EXPECT_GT(tally.paths_with_dirac, 0);
      // Negative control: weights that do not know the Dirac vertices give weight to connections
      // through them.
      o.drop_dirac_flags = true;
      MisInvariantTally broken;
      double ignored = 0.0;
      sample_mis_invariant(*world, file, o, &broken, &ignored);
      EXPECT_FALSE(broken.holds());
      EXPECT_GT(broken.nonzero_invalid, 0);
    }
  }
}

}  // namespace
}  // namespace tb

// The half-vector mutation (lib/mcmc/path_space/hslt_mutation.h; Kaplanyan 2014, Sec. 5, 6.1):
// registered outside the default mixture, step sizes of Sec. 6.1, proposals with a positive stated
// density both ways and kept endpoints, and the integrator "hslt" on a small glossy image.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {
namespace {

struct Glossy {
  std::unique_ptr<World> world = load_scene_at_resolution("glossy.json", 16, 16);
  LightSampler lights{*world};
  PathContext ctx{world.get(), &lights};
};

TEST(HsltMutation, RegisteredOutsideTheDefaultMixture) {
  const PathMutationInfo* info = find_path_mutation("hslt");
  ASSERT_NE(info, nullptr);
  EXPECT_FALSE(info->in_default_mixture);
  const Glossy g;
  for (const auto& m : make_path_mutations(g.ctx, {})) EXPECT_NE(m->name(), "hslt");
  EXPECT_NE(find_integrator("hslt"), nullptr);
}

TEST(HsltMutation, ProposalsHavePositiveDensityBothWaysAndKeepTheEndpoints) {
  const Glossy g;
  const HsltMutation m(g.ctx);
  const HsltMutation no_jump(g.ctx, HsltMutation::kDefaultGamma, nullptr, true, HsltMutation::kImageFraction, false);
  Rng rng = Rng::for_sample(1, 11, 0);
  RngUniforms u(rng);
  int paths = 0, proposed = 0, preempted = 0;
  for (int a = 0; a < 20000 && paths < 40; ++a) {
    const auto x = sample_bdpt_path(g.ctx, u, 3, 2);
    if (!x || !m.applicable(*x)) continue;
    ++paths;
    // Sec. 6.1: sigma = gamma alpha sqrt(2) / pi (expected 2D step gamma alpha / sqrt(pi)).
    const std::vector<double> s = m.sigmas(*x);
    for (int i = 1; i < x->segments(); ++i) {
      const double alpha = x->v[static_cast<size_t>(i)].bsdf->beckmann_roughness();
      const double a_used = std::isfinite(alpha) ? alpha : HsltMutation::kDiffuseAlpha;
      EXPECT_NEAR(s[static_cast<size_t>(i - 1)], 0.1 * a_used * std::sqrt(2.0) / kPi, 1e-15);
    }
    for (int t = 0; t < 3; ++t) {
      const auto y = m.propose(*x, u);
      if (!y) continue;
      ++proposed;
      ASSERT_EQ(y->segments(), x->segments());
      EXPECT_TRUE(same_vertex(x->v.front(), y->v.front()));
      EXPECT_TRUE(same_vertex(x->v.back(), y->v.back()));
      EXPECT_GT(m.density(*x, *y), 0.0);
      // A subspace jump (Sec. 5.2) need not be reversible by a jump; a regular move is reversible
      // by the regular branch (T > 0 without jumps), which a jump from y towards H(x) may preempt.
      if (!(m.jump_density(*x, *y) > 0.0)) {
        EXPECT_GT(no_jump.density(*y, *x), 0.0);
        preempted += !(m.density(*y, *x) > 0.0);
      }
    }
  }
  EXPECT_EQ(paths, 40);
  EXPECT_GT(proposed, 60);
  EXPECT_LE(10 * preempted, proposed);
  const HsltCountsSnapshot c = snapshot(*m.counters());
  EXPECT_EQ(c.generated, proposed);
  EXPECT_GE(c.proposals, c.generated);
}

// Sec. 5.2: with gamma = 1 jumps occur; each has a positive stated jump density, zero regular
// density (the branches are exclusive), is bidirectionally invalid, and the counters are ordered;
// with the option off no jump is proposed.
TEST(HsltMutation, SubspaceJumpsAreExclusiveOfTheRegularBranch) {
  const Glossy g;
  for (const bool jump : {true, false}) {
    const HsltMutation m(g.ctx, 1.0, nullptr, false, HsltMutation::kImageFraction, jump);
    Rng rng = Rng::for_sample(1, 12, jump ? 1 : 0);
    RngUniforms u(rng);
    int jumps = 0, reversible_jumps = 0;
    for (int a = 0; a < 20000 && jumps < 20; ++a) {
      const auto x = sample_bdpt_path(g.ctx, u, 3, 2);
      if (!x || !m.applicable(*x)) continue;
      const auto y = m.propose(*x, u);
      if (!y || !(m.jump_density(*x, *y) > 0.0)) continue;
      ++jumps;
      EXPECT_TRUE(m.bidirectionally_invalid(*x, *y));
      const HsltMutation::DensityParts p = m.density_parts(*x, *y);
      EXPECT_FALSE(p.structure && p.forward_lands && p.reverse_lands);
      EXPECT_DOUBLE_EQ(m.density(*x, *y), m.jump_density(*x, *y));
      reversible_jumps += m.density(*y, *x) > 0.0;
    }
    const HsltCountsSnapshot c = snapshot(*m.counters());
    EXPECT_LE(c.jump_succeeded, c.jump_projected);
    EXPECT_LE(c.jump_projected, c.jump_attempted);
    if (jump) {
      EXPECT_EQ(jumps, 20);
      EXPECT_EQ(c.jump_succeeded, jumps);
      EXPECT_GT(reversible_jumps, 0);
    } else {
      EXPECT_EQ(jumps, 0);
      EXPECT_EQ(c.jump_attempted, 0);
    }
  }
}

// Sec. 6.2-6.3: the stratified step is never larger than the BSDF step on either axis, and without
// stratification it is sigma I.
TEST(HsltMutation, StratifiedStepsAreBoundedByTheBsdfSteps) {
  const Glossy g;
  const HsltMutation strat(g.ctx), plain(g.ctx, HsltMutation::kDefaultGamma, nullptr, false);
  Rng rng = Rng::for_sample(1, 12, 0);
  RngUniforms u(rng);
  int paths = 0, smaller = 0;
  for (int a = 0; a < 20000 && paths < 40; ++a) {
    const auto x = sample_bdpt_path(g.ctx, u, 3, 2);
    if (!x || !strat.applicable(*x)) continue;
    ++paths;
    const auto X = strat.hslt_path(*x);
    ASSERT_TRUE(X);
    const std::vector<double> s = strat.sigmas(*x);
    const auto L = strat.step_factors(*x, *X), L0 = plain.step_factors(*x, *X);
    for (size_t r = 0; r < s.size(); ++r) {
      EXPECT_TRUE(L0[r].isApprox(s[r] * Eigen::Matrix2d::Identity()) || s[r] == 0.0);
      const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(L[r]).singularValues();
      EXPECT_LE(sv(0), s[r] * (1 + 1e-12));
      smaller += sv(1) < 0.999 * s[r] ? 1 : 0;
    }
  }
  EXPECT_EQ(paths, 40);
  EXPECT_GT(smaller, 0);  // the image-space step is the smaller one somewhere
}

TEST(HsltMutation, IntegratorRendersAFiniteImage) {
  const auto world = load_scene_at_resolution("glossy.json", 8, 8);
  Film film(8, 8);
  RenderSettings s;
  s.spp = 64;
  s.passes = 4;
  s.max_depth = 3;
  EXPECT_EQ(render_hslt(*world, s, film), 4);
  const auto img = film.mean_image();
  double sum = 0.0;
  for (const auto& p : img) {
    EXPECT_TRUE(std::isfinite(p.r) && std::isfinite(p.g) && std::isfinite(p.b));
    sum += p.r + p.g + p.b;
  }
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace tb::path_space

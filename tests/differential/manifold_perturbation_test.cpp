// The manifold perturbation (lib/mcmc/path_space/manifold_perturbation.h; Jakob and Marschner 2012):
// registered outside the default mixture, applies exactly where the lens perturbation cannot join
// (a specular vertex behind the first non-specular one), proposals keep the fixed vertices and
// satisfy the specular constraints, both densities positive, the generalised geometry term of the
// block LU equals the dense determinant, and the integrator "memlt" on a small caustic image.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/film/film.h"
#include "lib/mcmc/path_space/manifold_perturbation.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/dirac.h"
#include "lib/path/light_sampler.h"
#include "lib/registry/integrator_registry.h"
#include "validate/mcmc/manifold_broken.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {
namespace {

struct Loaded {
  explicit Loaded(const char* file) : world(load_scene_at_resolution(file, 16, 16)), lights(*world), ctx{world.get(), &lights} {}
  std::unique_ptr<World> world;
  LightSampler lights;
  PathContext ctx;
};

TEST(ManifoldPerturbation, RegisteredOutsideTheDefaultMixture) {
  const PathMutationInfo* info = find_path_mutation("manifold");
  ASSERT_NE(info, nullptr);
  EXPECT_FALSE(info->in_default_mixture);
  const Loaded g("caustic.json");
  for (const auto& m : make_path_mutations(g.ctx, {})) EXPECT_NE(m->name(), "manifold");
  EXPECT_NE(find_integrator("memlt"), nullptr);
}

// Where it applies, x_{j-1} is specular (so the lens perturbation does not), and nowhere on the
// diffuse Cornell box.
TEST(ManifoldPerturbation, AppliesWhereTheLensPerturbationCannotJoin) {
  const Loaded g("caustic.json");
  const ManifoldPerturbation m(g.ctx);
  Rng rng = Rng::for_sample(3, 17, 0);
  RngUniforms u(rng);
  int applicable = 0;
  for (int a = 0; a < 20000; ++a) {
    const auto x = sample_bdpt_path(g.ctx, u, 5, 3);
    if (!x || !m.applicable(*x)) continue;
    ++applicable;
    const int j = m.chain_end(*x), c = m.chain_start(*x);
    EXPECT_TRUE(is_dirac_surface(x->v[static_cast<size_t>(j - 1)]));
    EXPECT_FALSE(m.lens().applicable(*x));
    EXPECT_LT(c, j - 1);
    for (int i = c + 1; i < j; ++i) EXPECT_TRUE(is_dirac_surface(x->v[static_cast<size_t>(i)]));
  }
  EXPECT_GT(applicable, 10);
  const Loaded box("cornell-box.json");
  const ManifoldPerturbation mb(box.ctx);
  for (int a = 0; a < 2000; ++a) {
    if (const auto x = sample_bdpt_path(box.ctx, u, 5, 1)) {
      EXPECT_FALSE(mb.applicable(*x));
    }
  }
}

TEST(ManifoldPerturbation, ProposalsSatisfyTheConstraintsAndHavePositiveDensityBothWays) {
  const Loaded g("caustic.json");
  const ManifoldPerturbation m(g.ctx);
  Rng rng = Rng::for_sample(1, 23, 0);
  RngUniforms u(rng);
  int paths = 0, proposed = 0;
  for (int a = 0; a < 200000 && paths < 30; ++a) {
    const auto x = sample_bdpt_path(g.ctx, u, 4, 3);
    if (!x || !m.applicable(*x)) continue;
    ++paths;
    for (int t = 0; t < 4; ++t) {
      const auto y = m.propose(*x, u);
      if (!y) continue;
      ++proposed;
      ASSERT_EQ(y->segments(), x->segments());
      const int c = m.chain_start(*x), j = m.chain_end(*x);
      for (int i = 0; i <= c; ++i) EXPECT_TRUE(same_vertex(x->v[static_cast<size_t>(i)], y->v[static_cast<size_t>(i)]));
      EXPECT_TRUE(same_vertex(x->v.back(), y->v.back()));
      // Kaplanyan 2014, Sec. 4.4: h^perp = 0 at the re-solved specular vertices (walk tolerance 1e-11).
      const std::optional<HsltPath> S = m.hslt().hslt_path(m.subpath(*y));
      ASSERT_TRUE(S.has_value());
      EXPECT_LT(hslt_constraints(*S).norm(), 1e-10);
      EXPECT_NE(glm::length(y->v[static_cast<size_t>(j)].hit.p - x->v[static_cast<size_t>(j)].hit.p), 0.0);
      const double fwd = m.density(*x, *y), rev = m.density(*y, *x);
      EXPECT_GT(fwd, 0.0);
      EXPECT_GT(rev, 0.0);
      // The block LU geometry term against the dense determinant (manifold_broken.h).
      const double g_lu = m.geometry_term(*y), g_dense = manifold_dense_geometry(m, *y);
      EXPECT_NEAR(g_lu / g_dense, 1.0, 1e-9);
      EXPECT_NEAR(manifold_reference_density(m, *x, *y) / fwd, 1.0, 1e-9);
    }
  }
  EXPECT_EQ(paths, 30);
  EXPECT_GT(proposed, 20);
  const HsltCountsSnapshot c = snapshot(*m.counters());
  EXPECT_EQ(c.generated, proposed);
  EXPECT_GE(c.proposals, c.generated);
  EXPECT_GE(c.converged, c.generated);
}

// The negative controls' faults change the stated density.
TEST(ManifoldPerturbation, BrokenVariantsStateAnotherDensity) {
  const Loaded g("caustic.json");
  const ManifoldPerturbation m(g.ctx);
  const ManifoldBrokenDensity none(m, ManifoldBrokenDensity::Fault::kNoGeometryTerm);
  const ManifoldBrokenDensity tr(m, ManifoldBrokenDensity::Fault::kTransposedBlock);
  Rng rng = Rng::for_sample(2, 29, 0);
  RngUniforms u(rng);
  int compared = 0, differ_none = 0, differ_tr = 0;
  for (int a = 0; a < 200000 && compared < 20; ++a) {
    const auto x = sample_bdpt_path(g.ctx, u, 4, 3);
    if (!x || !m.applicable(*x)) continue;
    const auto y = m.propose(*x, u);
    if (!y) continue;
    ++compared;
    const double t = m.density(*x, *y);
    differ_none += std::abs(none.density(*x, *y) / t - 1.0) > 1e-6;
    differ_tr += std::abs(tr.density(*x, *y) / t - 1.0) > 1e-6;
  }
  EXPECT_EQ(compared, 20);
  EXPECT_EQ(differ_none, 20);
  EXPECT_GT(differ_tr, 0);
}

TEST(ManifoldPerturbation, IntegratorRendersAFiniteImage) {
  const auto world = load_scene_at_resolution("caustic.json", 8, 8);
  Film film(8, 8);
  RenderSettings s;
  s.spp = 64;
  s.passes = 4;
  s.max_depth = 4;
  EXPECT_EQ(render_memlt(*world, s, film), 4);
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

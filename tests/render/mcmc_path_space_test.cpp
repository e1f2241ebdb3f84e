// Veach's path-space MLT (lib/mcmc/path_space/, docs/mlt-path-space.md), on the Cornell box
// (16 x 16) and the glossy scene:
//  - pairwise detailed balance pi(x) T(x->y) a(x->y) = pi(y) T(y->x) a(y->x) to 1e-9 relative for
//    each mutation (bidirectional, lens, caustic) and for the driver's mixture kernel, with the
//    acceptance built from the mutation's stated T and the flux from the independent reference
//    density of reference_density.h;
//  - chi-square of proposal samples against the stated density in low-dimensional projections
//    (proposal_projections.h), alpha = 1e-5 per test;
//  - net flux of the mixture kernel (net_flux.h) and image unbiasedness of render_mlt against
//    BDPT with chains as Welch samples;
//  - negative controls that must be caught: the lens perturbation without its T ratio, the
//    bidirectional density without its geometry term, Metropolis-only acceptance.
//  - Dirac vertices (caustic.json, dg-glass.json, dg-mirror-chain.json): f / p against BDPT's
//    weights, pairwise balance of the mixture from Dirac start paths, the caustic image.
// Fixed seeds throughout.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <gtest/gtest.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/proposal_mixture.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/caustic_perturbation.h"
#include "lib/mcmc/path_space/mlt.h"
#include "validate/mcmc/path_space/net_flux.h"
#include "validate/mcmc/path_space/proposal_projections.h"
#include "validate/mcmc/path_space/reference_density.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/mcmc/path_space/subpath_step.h"
#include "lib/path/dirac.h"
#include "lib/path/light_sampler.h"
#include "lib/path/measure.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/broken_variants.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/render/broken_path_mutations.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb::path_space {
namespace {

constexpr int kMaxDepth = 4;  // max_segments 5
constexpr double kAlpha = 1e-5;

struct Scene {
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
  explicit Scene(int res = 16, const char* file = "cornell-box.json") {
    setenv("TB_SCENES_DIR", TB_SOURCE_DIR "/scenes", 0);
    world = load_scene_at_resolution(file, res, res);
    lights = std::make_unique<LightSampler>(*world);
    ctx = PathContext{world.get(), lights.get()};
  }
};

Scene& cornell() {
  static Scene s;
  return s;
}

std::function<MltPath(Uniforms&)> start_sampler(const PathContext& ctx, int min_segments = 1) {
  return [&ctx, min_segments](Uniforms& u) {
    auto x = sample_bdpt_path(ctx, u, kMaxDepth, min_segments);
    return x ? *x : MltPath{};
  };
}

PathMutationSettings settings() {
  PathMutationSettings s;
  s.max_segments = kMaxDepth + 1;
  return s;
}
PathMutationList registered(const PathContext& ctx) { return make_path_mutations(ctx, settings()); }
// Reference density of component j of a mixture of registered mutations.
auto reference_of(const PathMixture& mix, const PathContext& ctx) {
  std::vector<std::function<double(const MltPath&, const MltPath&)>> refs;
  for (int j = 0; j < mix.components(); ++j) refs.push_back(reference_density_of(mix.component(j), ctx));
  return [refs](int j, const MltPath& x, const MltPath& y) { return refs[static_cast<size_t>(j)](x, y); };
}
// The registered lens perturbation with its T ratio dropped (broken_path_mutations.h).
std::shared_ptr<const PathMutation> broken_lens(const PathContext& ctx) {
  return std::make_shared<const LensWithoutDensityRatio>(
      std::make_shared<const PathProposalMutation<LensPerturbation>>("lens", 1.0, LensPerturbation(ctx)));
}

template <class Mut, class Rule = mcmc::HastingsRatio>
auto make_kernel(const PathContext& ctx, Mut mut, Rule rule = {}) {
  return mcmc::MetropolisHastings(PathTarget{&ctx}, mcmc::SingleProposal<Mut>(std::move(mut)), rule);
}

template <class K, class Ref>
mcmc::PairwiseBalanceResult pairwise(const K& kernel, Ref ref, const PathContext& ctx, const char* name, int pairs) {
  const WithReferenceDensity<K, Ref> k(kernel, ref, 8);  // pairs with flux (reference_density.h)
  return mcmc::check_pairwise_balance<WithReferenceDensity<K, Ref>>(k, start_sampler(ctx), pairs, 11,
                                                                    hash_string(name));
}

// ---- bidirectional mutation -------------------------------------------------------------------------

TEST(PathSpaceMlt, BidirectionalStatedDensityEqualsReference) {
  const Scene& sc = cornell();
  const BidirectionalMutation mut(sc.ctx, kMaxDepth + 1);
  double worst = 0.0;
  int live = 0;
  for (uint64_t i = 0; i < 300; ++i) {
    Rng r = Rng::for_sample(3, 5, i);
    RngUniforms u(r);
    const auto x = sample_bdpt_path(sc.ctx, u, kMaxDepth);
    ASSERT_TRUE(x);
    const auto y = mut.propose(*x, u);
    if (!y) continue;
    const double a = mut.density(*x, *y), b = reference_density(mut, *x, *y);
    ASSERT_GT(a, 0.0) << "pair " << i;
    worst = std::max(worst, std::abs(a - b) / std::max(a, b));
    ++live;
  }
  EXPECT_GT(live, 150);
  EXPECT_LT(worst, 1e-12);
}

TEST(PathSpaceMlt, BidirectionalPairwiseBalance) {
  const Scene& sc = cornell();
  const auto kernel = make_kernel(sc.ctx, BidirectionalMutation(sc.ctx, kMaxDepth + 1));
  const auto ref = [&](int, const MltPath& x, const MltPath& y) {
    return reference_density(kernel.mixture().proposal(), x, y);
  };
  const auto r = pairwise(kernel, ref, sc.ctx, "bidir", 400);
  std::printf("bidirectional pairwise: %s\n", r.message.c_str());
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(PathSpaceMlt, BidirectionalMissingGeometryTermIsCaught) {
  const Scene& sc = cornell();
  const BidirWithoutGeometryTerm broken(sc.ctx, kMaxDepth + 1);
  const auto kernel = make_kernel(sc.ctx, MutationProposal{&broken, nullptr});
  const BidirectionalMutation correct(sc.ctx, kMaxDepth + 1);
  const auto ref = [&](int, const MltPath& x, const MltPath& y) { return reference_density(correct, x, y); };
  const auto r = pairwise(kernel, ref, sc.ctx, "bidir.nogeom", 400);
  std::printf("bidirectional without geometry term: %s\n", r.message.c_str());
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.violations, 20);
}

// Chi-square of one way of the bidirectional mutation (proposal_projections.h): the direction of
// the regenerated vertex against the stated density converted to solid angle.
SamplerChi2Result bidir_way_chi2(const BidirectionalMutation& mut, const MltPath& x, int s, int64_t samples,
                                 uint64_t key, const BidirWithoutGeometryTerm* broken = nullptr) {
  BidirWayProjection proj{&mut, x, s, nullptr};
  if (broken)
    proj.split_density = [broken](const MltPath& y, int l, int na, int sp) { return broken->split_density(y, l, na, sp); };
  SamplerChi2Options o;
  o.samples = samples;
  o.seed = 17;
  o.key = key;
  o.quadrature_max_depth = 3;
  return chi2_test(
      Chi2Domain::sphere(51, 25), [&](Uniforms& u) { return proj.sample(u); },
      [&](const Vec3& w) { return proj.pdf(w); }, o);
}

MltPath path_with_segments(const PathContext& ctx, int k, uint64_t seed) {
  return tb::path_space::path_with_segments(ctx, k, kMaxDepth, seed);
}

TEST(PathSpaceMlt, BidirectionalWayChi2) {
  const Scene& sc = cornell();
  const BidirectionalMutation mut(sc.ctx, kMaxDepth + 1);
  const BidirWithoutGeometryTerm broken(sc.ctx, kMaxDepth + 1);
  const MltPath x = path_with_segments(sc.ctx, 3, 5);
  for (int s : {0, 1}) {
    const auto r = bidir_way_chi2(mut, x, s, 200000, hash_string("bidir.chi2") + s);
    std::printf("bidirectional way chi2 (s' = %d): %s\n", s, r.message().c_str());
    EXPECT_TRUE(r.passed(kAlpha)) << r.message();
    const auto rb = bidir_way_chi2(mut, x, s, 200000, hash_string("bidir.chi2") + s, &broken);
    std::printf("  without geometry term: %s\n", rb.message().c_str());
    EXPECT_FALSE(rb.passed(kAlpha)) << rb.message();
  }
}

// ---- lens perturbation ------------------------------------------------------------------------------

TEST(PathSpaceMlt, LensPairwiseBalance) {
  const Scene& sc = cornell();
  const auto kernel = make_kernel(sc.ctx, LensPerturbation(sc.ctx));
  const auto ref = [&](int, const MltPath& x, const MltPath& y) {
    return reference_density(kernel.mixture().proposal(), sc.ctx, x, y);
  };
  const auto r = pairwise(kernel, ref, sc.ctx, "lens", 400);
  std::printf("lens pairwise: %s\n", r.message.c_str());
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(PathSpaceMlt, LensWithoutDensityRatioIsCaught) {
  const Scene& sc = cornell();
  const LensPerturbation correct(sc.ctx);
  const auto ref = [&](int, const MltPath& x, const MltPath& y) { return reference_density(correct, sc.ctx, x, y); };
  // The fault as a mutation stating T = const, and as the Metropolis-only acceptance rule.
  const auto broken = broken_lens(sc.ctx);
  const auto k1 = make_kernel(sc.ctx, MutationProposal{broken.get(), nullptr});
  const auto r1 = pairwise(k1, ref, sc.ctx, "lens.noratio", 400);
  std::printf("lens without T ratio: %s\n", r1.message.c_str());
  EXPECT_FALSE(r1.passed);
  EXPECT_GT(r1.violations, 20);
  const auto k2 = make_kernel(sc.ctx, LensPerturbation(sc.ctx), mcmc::MetropolisRatioOnly{});
  const auto r2 = pairwise(k2, ref, sc.ctx, "lens.metropolis", 400);
  EXPECT_FALSE(r2.passed);
}

// The lens perturbation's raster offset in polar coordinates (proposal_projections.h).
SamplerChi2Result lens_chi2(const LensPerturbation& lens, const PathContext& ctx, const MltPath& x, int64_t samples,
                            uint64_t key) {
  const LensOffsetProjection proj{&lens, &ctx, x};
  SamplerChi2Options o;
  o.samples = samples;
  o.seed = 19;
  o.key = key;
  return chi2_test(
      Chi2Domain::rectangle(proj.chart_lo(), proj.chart_hi(), 51, 51), [&](Uniforms& u) { return proj.sample(u); },
      [&](const Vec2& q) { return proj.pdf(q); }, o);
}

TEST(PathSpaceMlt, LensOffsetChi2) {
  const Scene& sc = cornell();
  const LensPerturbation lens(sc.ctx);
  const MltPath x = path_with_segments(sc.ctx, 2, 9);
  const auto r = lens_chi2(lens, sc.ctx, x, 200000, hash_string("lens.chi2"));
  std::printf("lens raster-offset chi2: %s\n", r.message().c_str());
  EXPECT_TRUE(r.passed(kAlpha)) << r.message();
}

// ---- caustic perturbation ---------------------------------------------------------------------------

TEST(PathSpaceMlt, CausticPairwiseBalance) {
  const Scene& sc = cornell();
  const auto kernel = make_kernel(sc.ctx, CausticPerturbation(sc.ctx));
  const auto ref = [&](int, const MltPath& x, const MltPath& y) {
    return reference_density(kernel.mixture().proposal(), x, y);
  };
  const auto r = pairwise(kernel, ref, sc.ctx, "caustic", 400);
  std::printf("caustic pairwise: %s\n", r.message.c_str());
  EXPECT_TRUE(r.passed) << r.message;
  const auto kb = make_kernel(sc.ctx, CausticPerturbation(sc.ctx), mcmc::MetropolisRatioOnly{});
  const auto rb = pairwise(kb, ref, sc.ctx, "caustic.metropolis", 400);
  EXPECT_FALSE(rb.passed) << rb.message;
}

TEST(PathSpaceMlt, CausticAngleChi2) {
  const Scene& sc = cornell();
  const CausticPerturbation caustic(sc.ctx);
  for (int k : {2, 3}) {
    const CausticAngleProjection proj{&caustic, path_with_segments(sc.ctx, k, 21)};
    SamplerChi2Options o;
    o.samples = 200000;
    o.seed = 23;
    o.key = hash_string("caustic.chi2") + k;
    o.quadrature_max_depth = 3;
    const auto r = chi2_test(
        Chi2Domain::rectangle(proj.chart_lo(), proj.chart_hi(), 51, 51), [&](Uniforms& u) { return proj.sample(u); },
        [&](const Vec2& q) { return proj.pdf(q); }, o);
    std::printf("caustic angle chi2 (k = %d): %s\n", k, r.message().c_str());
    if (getenv("VEACH_DEBUG")) std::printf("%s\n", r.details().dump().c_str());
    EXPECT_TRUE(r.passed(kAlpha)) << r.message();
  }
}

// ---- the mixture kernel with state-dependent selection ----------------------------------------------

TEST(PathSpaceMlt, MixturePairwiseBalance) {
  const Scene& sc = cornell();
  const BidirectionalMutation bidir(sc.ctx, kMaxDepth + 1);
  const PathMixture mix(registered(sc.ctx));
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mix);
  const auto ref = reference_of(mix, sc.ctx);
  const auto r = pairwise(kernel, ref, sc.ctx, "mixture", 600);
  std::printf("mixture pairwise: %s\n", r.message.c_str());
  EXPECT_TRUE(r.passed) << r.message;
  // Negative control: the acceptance without c_j(y) / c_j(x) (and T ratios).
  const auto kb = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mix, mcmc::MetropolisRatioOnly{});
  const auto rb = pairwise(kb, ref, sc.ctx, "mixture.metropolis", 600);
  EXPECT_FALSE(rb.passed) << rb.message;
}

// The glossy scene (GGX / Beckmann conductors, a rough dielectric sphere): the mixture kernel's
// pairwise balance with transmission and glossy lobes in the bidirectional densities, and the
// chi-square of the bidirectional ways there.
TEST(PathSpaceMlt, GlossySceneMixtureBalanceAndWays) {
  const Scene sc(16, "glossy.json");
  const BidirectionalMutation bidir(sc.ctx, kMaxDepth + 1);
  const PathMixture mix(registered(sc.ctx));
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mix);
  const auto ref = reference_of(mix, sc.ctx);
  const auto r = pairwise(kernel, ref, sc.ctx, "glossy.mixture", 600);
  std::printf("glossy mixture pairwise: %s\n", r.message.c_str());
  EXPECT_TRUE(r.passed) << r.message;
  for (int k : {3, 4})
    for (int s : {0, 1}) {
      const auto res = bidir_way_chi2(bidir, path_with_segments(sc.ctx, k, 31 + k), s, 100000,
                                      hash_string("glossy.way") + 10 * k + s);
      std::printf("glossy way chi2 (k = %d, s' = %d): %s\n", k, s, res.message().c_str());
      EXPECT_TRUE(res.passed(kAlpha)) << res.message();
    }
}

// ---- net flux (reversibility seen through antisymmetric statistics) ------------------------------
// One-sample t-tests of Z_c = b_c sum_t g(X_t, X_{t+1}) against 0 over independent chains
// (net_flux.h), Šidák over the statistics at alpha = 1e-5.
template <class K>
double net_flux_min_p(const K& kernel, const PathContext& ctx, uint64_t key, std::string* msg) {
  NetFluxOptions o;
  o.chains = 160;
  o.steps = 150;
  o.max_depth = kMaxDepth;
  o.seed = 41;
  o.key = key;
  const NetFluxSamples f = net_flux(kernel, ctx, o);
  double pmin = 1.0;
  for (size_t i = 0; i < f.names.size(); ++i) {
    stats::Welford w;
    for (double z : f.z[i]) w.add(z);
    const auto t = stats::one_sample_t_test(w, 0.0);
    pmin = std::min(pmin, t.p_value);
    *msg += f.names[i] + ": p = " + std::to_string(t.p_value) + "  ";
  }
  return 1.0 - std::pow(1.0 - pmin, static_cast<double>(f.names.size()));  // Šidák
}

TEST(PathSpaceMlt, NetFluxOfMixtureAndNegativeControls) {
  const Scene& sc = cornell();
  std::string m;
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, PathMixture(registered(sc.ctx)));
  const double p = net_flux_min_p(kernel, sc.ctx, 1, &m);
  std::printf("net flux, mixture: Sidak p = %.3g (%s)\n", p, m.c_str());
  EXPECT_GT(p, kAlpha) << m;
  m.clear();
  const auto kb = mcmc::MetropolisHastings(PathTarget{&sc.ctx},
                                           PathMixture(with_bidir_without_geometry_term(sc.ctx, settings())));
  const double pb = net_flux_min_p(kb, sc.ctx, 2, &m);
  std::printf("net flux, bidirectional without geometry term: Sidak p = %.3g (%s)\n", pb, m.c_str());
  EXPECT_LT(pb, kAlpha) << m;
  m.clear();
  const auto kl = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, PathMixture({broken_lens(sc.ctx)}));
  const double pl = net_flux_min_p(kl, sc.ctx, 3, &m);
  std::printf("net flux, lens without T ratio: Sidak p = %.3g (%s)\n", pl, m.c_str());
}

// ---- the driver -------------------------------------------------------------------------------------

TEST(PathSpaceMlt, RenderRunsAndReportsAcceptance) {
  const Scene& sc = cornell();
  Film film(16, 16);
  RenderSettings st;
  st.spp = 64;
  st.passes = 8;
  st.max_depth = kMaxDepth;
  st.seed = 3;
  const MltStats s = run_mlt(*sc.world, st, film);
  EXPECT_EQ(s.chains, 8);
  EXPECT_EQ(film.passes(), 8);
  EXPECT_EQ(s.chains_without_start, 0);
  for (const auto& m : s.mutations) {
    std::printf("%s: proposed %lld, failed %lld, acceptance %.3f\n", m.name.c_str(),
                static_cast<long long>(m.proposed), static_cast<long long>(m.failed), m.acceptance_rate());
    // The Cornell box has no specular vertex: the multi-chain perturbation is never selected.
    if (m.name == "multi-chain")
      EXPECT_EQ(m.proposed, 0);
    else
      EXPECT_GT(m.accepted, 0) << m.name;
  }
  std::printf("b = %.5g, %.0f mutations/s\n", s.b_mean, s.mutations_per_second());
  // Each mutation alone (timing and acceptance per type; single-threaded chains in parallel).
  for (int j = 0; j < 3; ++j) {
    MltOptions o;
    o.mutations = [j](const PathContext& ctx, const PathMutationSettings& ms) {
      PathMutationList all = make_path_mutations(ctx, ms), one;
      one.push_back(all[static_cast<size_t>(j)]);
      // k = 1 paths need some other move than the caustic perturbation.
      if (j == 2) one.push_back(std::make_shared<const PathProposalMutation<LensPerturbation>>("lens", 1e-9, LensPerturbation(ctx)));
      return one;
    };
    Film f1(16, 16);
    const MltStats one = run_mlt(*sc.world, st, f1, o);
    std::printf("  %s alone: acceptance %.3f, %.0f mutations/s\n", one.mutations[0].name.c_str(),
                one.mutations[0].acceptance_rate(), one.mutations_per_second());
  }
  // Deterministic: the same seed gives the same image, on one thread too.
  Film again(16, 16);
  {
    const ThreadLimit one(1);
    run_mlt(*sc.world, st, again);
  }
  const auto a = film.mean_image(), b = again.mean_image();
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << i;
}


// ---- image unbiasedness against BDPT ------------------------------------------------------------
// Every chain of render_mlt is one Welch sample (b_c times its chain average); the chains are
// independent, and E[b_c g(X_t)] = int g f for every t when the start is resampled from the
// bootstrap that gives b_c and the kernel keeps pi invariant, so the image is unbiased.
// Per pixel-channel Welch tests against a BDPT reference (compare_channels: Šidák over pixels and
// channels, Stouffer and sum z^2), alpha = 1e-4. Negative control: the bidirectional mutation
// with its geometry term dropped biases the image and must be rejected.
ChannelCompare mlt_vs_bdpt(const MltOptions& opt, MltStats* stats, const char* file = "cornell-box.json") {
  const Scene sc(8, file);
  const WelchImage reference = [&] {
    Film f(8, 8);
    RenderSettings st;
    st.spp = 2048;
    st.passes = 32;
    st.max_depth = 3;
    st.seed = 101;
    render_bdpt(*sc.world, st, f);
    return f.welch();
  }();
  Film film(8, 8);
  RenderSettings st;
  st.passes = 48;      // chains
  st.spp = 48 * 160;   // mutations per pixel in total: 10240 per chain
  st.max_depth = 3;
  st.seed = 7;
  *stats = run_mlt(*sc.world, st, film, opt);
  return compare_channels(film.welch(), reference, 1e-4);
}

TEST(PathSpaceMlt, ImageUnbiasedAgainstBdpt) {
  MltStats s;
  const auto c = mlt_vs_bdpt({}, &s);
  std::printf("mlt vs bdpt: %s\n", c.message().c_str());
  std::printf("  %.0f mutations/s; acceptance bidirectional %.3f, lens %.3f\n", s.mutations_per_second(),
              s.mutations[0].acceptance_rate(), s.mutations[1].acceptance_rate());
  EXPECT_FALSE(c.rejects()) << c.message();
  MltOptions broken;
  broken.mutations = with_bidir_without_geometry_term;
  const auto cb = mlt_vs_bdpt(broken, &s);
  std::printf("mlt (bidirectional without geometry term) vs bdpt: %s\n", cb.message().c_str());
  EXPECT_TRUE(cb.rejects()) << cb.message();
}

// The glossy scene (rough conductors and a rough dielectric: no Dirac vertices).
TEST(PathSpaceMlt, GlossyImageUnbiasedAgainstBdpt) {
  MltStats s;
  const auto c = mlt_vs_bdpt({}, &s, "glossy.json");
  std::printf("glossy mlt vs bdpt: %s\n", c.message().c_str());
  EXPECT_FALSE(c.rejects()) << c.message();
}

// ---- Dirac vertices (lib/path/dirac.h) ------------------------------------------------------------------
Scene& caustic_scene() {
  static Scene s(16, "caustic.json");
  return s;
}

bool has_dirac(const MltPath& x) {
  for (const auto& v : x.v)
    if (is_dirac_surface(v)) return true;
  return false;
}

// f(X) / p_{s,t}(X) with the Dirac coefficients and pseudo densities equals BDPT's unweighted
// contribution of connection (s, t) for paths through the glass sphere: the convention of dirac.h
// reproduces the sampling weights of both walk directions (radiance and importance mode).
TEST(PathSpaceMlt, DiracFOverDensityEqualsBdptWeight) {
  Scene& sc = caustic_scene();
  const Camera& cam = sc.world->camera();
  std::vector<PathVertex> cp, lp;
  int checked = 0, dirac_paths = 0;
  for (uint64_t i = 0; i < 4000; ++i) {
    Rng r = Rng::for_sample(3, 0xd1cULL, i);
    RngUniforms u(r);
    const Vec2 uf = u.next2(), lens_u = u.next2();
    const int nc = generate_camera_subpath(sc.ctx, Vec2(uf.x * cam.width(), uf.y * cam.height()), lens_u, u, 6, &cp);
    const int nl = generate_light_subpath(sc.ctx, u, 5, &lp);
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t < 2 || s + t - 2 > kMaxDepth) continue;
        const Connection c = connect_bdpt(sc.ctx, lp, cp, s, t, u);
        if (!(luminance(c.unweighted) > 0.0)) continue;
        const MltPath x = assemble_connection(lp, cp, s, t, c);
        const Rgb f = measurement_contribution(sc.ctx, x.v, true, DiracPolicy::kCoefficient);
        const double p = technique_density(path_densities(sc.ctx, x.v, DiracPolicy::kCoefficient), s);
        ASSERT_GT(p, 0.0) << "i " << i << " s " << s << " t " << t;
        const double a = luminance(f) / p, b = luminance(c.unweighted);
        EXPECT_NEAR(a / b, 1.0, 1e-6) << "i " << i << " s " << s << " t " << t << " k " << x.segments();
        ++checked;
        dirac_paths += has_dirac(x) ? 1 : 0;
      }
  }
  std::printf("checked %d connections, %d through Dirac vertices\n", checked, dirac_paths);
  EXPECT_GT(dirac_paths, 50);
}


// Start paths through at least one Dirac vertex (BDPT samples, redrawn from the same stream).
std::function<MltPath(Uniforms&)> dirac_start_sampler(const PathContext& ctx) {
  return [&ctx](Uniforms& u) {
    for (int a = 0; a < 256; ++a) {
      auto x = sample_bdpt_path(ctx, u, kMaxDepth);
      if (x && has_dirac(*x)) return *x;
    }
    return MltPath{};
  };
}

// Pairwise detailed balance of every mutation and of the mixture on paths through the glass
// sphere of caustic.json (specular chains in f, in the lens / caustic chains and in the
// bidirectional pseudo densities).
TEST(PathSpaceMlt, DiracPairwiseBalance) {
  for (const char* file : {"caustic.json", "dg-glass.json", "dg-mirror-chain.json"}) {
    Scene sc(16, file);
    const PathMixture mix(registered(sc.ctx));
    const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mix);
    using K = decltype(kernel);
    const auto ref = reference_of(mix, sc.ctx);
    const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, 8);
    const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(
        k, dirac_start_sampler(sc.ctx), 600, 11, hash_string(file));
    std::printf("%s mixture pairwise (Dirac starts): %s\n", file, r.message.c_str());
    EXPECT_TRUE(r.passed) << file << ": " << r.message;
  }
}


// The caustic scene through the glass sphere: render_mlt (default mixture) against BDPT.
TEST(PathSpaceMlt, CausticImageUnbiasedAgainstBdpt) {
  MltStats s;
  const auto c = mlt_vs_bdpt({}, &s, "caustic.json");
  std::printf("caustic mlt vs bdpt: %s\n", c.message().c_str());
  EXPECT_FALSE(c.rejects()) << c.message();
}

}  // namespace
}  // namespace tb::path_space

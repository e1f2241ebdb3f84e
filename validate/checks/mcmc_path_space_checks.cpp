// Checks of Veach's path-space MLT mutations (lib/mcmc/path_space/, docs/mlt-path-space.md) on
// the Cornell box at 16 x 16 pixels (VALIDATION.md E and A, issue 6 "Checks on light paths"):
//  - mlt.path_space.<mutation>.pairwise: pi(x) T(x->y) a(x->y) = pi(y) T(y->x) a(y->x) to 1e-9
//    relative on seeded path pairs (x from BDPT, y proposed by the mutation), with the acceptance
//    built by the estimators' Metropolis-Hastings kernel from the mutation's stated T and the
//    flux from the reference density of reference_density.h (deterministic);
//  - mlt.path_space.<mutation>.<projection>_chi2: proposal samples against the stated density in
//    a low-dimensional projection (proposal_projections.h), alpha = 1e-5 per check, Šidák over
//    its configurations;
//  - mlt.path_space.mixture.pairwise: the same for the driver's mixture kernel (length-dependent
//    selection probabilities in the ratio);
//  - mlt.path_space.mixture.net_flux: zero net flux of the mixture kernel in path length, raster
//    position and ln pi (net_flux.h: chains from importance-resampled starts, t-tests over chains);
//  - mlt.path_space.image.cornell: render_mlt against BDPT with chains as Welch samples;
//  - negative controls, passing when the broken variant IS rejected: the lens perturbation with
//    its T ratio dropped (pairwise), the bidirectional density without a geometry term (pairwise,
//    chi-square, net flux and image), the mixture accepting with pi(y) / pi(x) only (pairwise).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/proposal_mixture.h"
#include "lib/core/hash.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/net_flux.h"
#include "lib/mcmc/path_space/proposal_projections.h"
#include "lib/mcmc/path_space/reference_density.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/broken_variants.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb {
namespace {

using namespace tb::path_space;
constexpr double kAlpha = 1e-5;
constexpr int kMaxDepth = 4;  // paths of up to 5 segments
constexpr int kResolution = 16;

struct CornellScene {
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
};

const CornellScene& cornell() {
  static const CornellScene s = [] {
    CornellScene c;
    c.world = load_scene_at_resolution("cornell-box.json", kResolution, kResolution);
    c.lights = std::make_unique<LightSampler>(*c.world);
    c.ctx = PathContext{c.world.get(), c.lights.get()};
    return c;
  }();
  return s;
}

CheckResult negate(CheckResult inner) {
  inner.passed = !inner.passed;
  inner.message =
      (inner.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + inner.message;
  return inner;
}

// ---- pairwise detailed balance ----------------------------------------------------------------------
template <class Mut, class Ref>
CheckResult run_pairwise(const Mut& mut, Ref ref, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mcmc::SingleProposal<Mut>(mut));
  using K = decltype(kernel);
  const auto r0 = [&](int, const MltPath& x, const MltPath& y) { return ref(x, y); };
  const WithReferenceDensity<K, decltype(r0)> k(kernel, r0, 8);
  const std::function<MltPath(Uniforms&)> start = [&](Uniforms& u) {
    auto x = sample_bdpt_path(sc.ctx, u, kMaxDepth);
    return x ? *x : MltPath{};
  };
  const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(r0)>>(
      k, start, cx.size(400, 10000), cx.seed, hash_string(name));
  CheckResult res;
  res.passed = r.passed;
  res.statistic_name = "max relative |F - B|";
  res.statistic = r.max_rel_residual;
  res.samples = r.pairs;
  res.message = r.message;
  res.details = {{"live_pairs", r.live},
                 {"violations", r.violations},
                 {"worst_index", r.worst_index},
                 {"failed_proposals", r.failed_proposals},
                 {"tolerance", r.tolerance},
                 {"reproducer", fmt::format("Rng::for_sample(seed, hash_string(\"{}\"), {})", name, r.worst_index)}};
  return res;
}

CheckResult bidir_pairwise(BidirFault fault, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const BidirectionalMutation correct(sc.ctx, kMaxDepth + 1);
  return run_pairwise(BidirectionalMutation(sc.ctx, kMaxDepth + 1, fault),
                      [&](const MltPath& x, const MltPath& y) { return reference_density(correct, x, y); }, cx, name);
}

CheckResult lens_pairwise(LensFault fault, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const LensPerturbation correct(sc.ctx);
  return run_pairwise(LensPerturbation(sc.ctx, 0.1, 0.0, fault),
                      [&](const MltPath& x, const MltPath& y) { return reference_density(correct, sc.ctx, x, y); },
                      cx, name);
}

CheckResult caustic_pairwise(const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const CausticPerturbation c(sc.ctx);
  return run_pairwise(c, [&](const MltPath& x, const MltPath& y) { return reference_density(c, x, y); }, cx, name);
}

// The driver's kernel: the mixture of all three with length-dependent selection c_j(x).
template <class Rule>
CheckResult mixture_pairwise(Rule rule, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const BidirectionalMutation bidir(sc.ctx, kMaxDepth + 1);
  const LensPerturbation lens(sc.ctx);
  const CausticPerturbation caustic(sc.ctx);
  const auto kernel =
      mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mcmc::Mixture(MutationSelection{}, bidir, lens, caustic), rule);
  using K = decltype(kernel);
  const auto ref = [&](int j, const MltPath& x, const MltPath& y) {
    return j == 0 ? reference_density(bidir, x, y)
                  : j == 1 ? reference_density(lens, sc.ctx, x, y) : reference_density(caustic, x, y);
  };
  const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, 8);
  const std::function<MltPath(Uniforms&)> start = [&](Uniforms& u) {
    auto x = sample_bdpt_path(sc.ctx, u, kMaxDepth);
    return x ? *x : MltPath{};
  };
  const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(
      k, start, cx.size(600, 10000), cx.seed, hash_string(name));
  CheckResult res;
  res.passed = r.passed;
  res.statistic_name = "max relative |F - B|";
  res.statistic = r.max_rel_residual;
  res.samples = r.pairs;
  res.message = r.message;
  res.details = {{"live_pairs", r.live}, {"violations", r.violations}, {"worst_index", r.worst_index},
                 {"tolerance", r.tolerance}};
  return res;
}

// ---- chi-square in projections --------------------------------------------------------------------
CheckResult chi2_record(const std::vector<std::pair<std::string, SamplerChi2Result>>& runs, const std::string& what) {
  const double alpha_each = 1.0 - std::pow(1.0 - kAlpha, 1.0 / static_cast<double>(runs.size()));  // Šidák
  CheckResult res;
  res.passed = true;
  res.statistic_name = "min p";
  res.statistic = 1.0;
  res.alpha = alpha_each;
  std::string msg;
  for (const auto& [label, r] : runs) {
    res.passed = res.passed && r.passed(alpha_each);
    res.statistic = std::min(res.statistic, r.p_value());
    res.samples += r.samples;
    res.details[label] = r.details();
    msg += fmt::format("{}{}: {}", msg.empty() ? "" : "; ", label, r.message());
  }
  res.p_value = res.statistic;
  res.message = what + ": " + msg;
  return res;
}

CheckResult bidir_chi2(BidirFault fault, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const BidirectionalMutation mut(sc.ctx, kMaxDepth + 1, fault);
  std::vector<std::pair<std::string, SamplerChi2Result>> runs;
  for (int k : {3, 4})
    for (int s : {0, 1}) {
      const BidirWayProjection proj{&mut, path_with_segments(sc.ctx, k, kMaxDepth, cx.seed + k), s};
      SamplerChi2Options o;
      o.samples = cx.size(100000, 1000000);
      o.seed = cx.seed;
      o.key = hash_values(hash_string(name), static_cast<uint64_t>(10 * k + s));
      o.quadrature_max_depth = 3;
      runs.emplace_back(fmt::format("k={} s'={}", k, s),
                        chi2_test(
                            Chi2Domain::sphere(51, 25), [&](Uniforms& u) { return proj.sample(u); },
                            [&](const Vec3& w) { return proj.pdf(w); }, o));
    }
  return chi2_record(runs, "direction of the regenerated vertex x_{k-2}");
}

CheckResult lens_chi2(const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const LensPerturbation lens(sc.ctx);
  std::vector<std::pair<std::string, SamplerChi2Result>> runs;
  for (int k : {1, 2, 3}) {
    const LensOffsetProjection proj{&lens, &sc.ctx, path_with_segments(sc.ctx, k, kMaxDepth, cx.seed + 10 + k)};
    SamplerChi2Options o;
    o.samples = cx.size(100000, 1000000);
    o.seed = cx.seed;
    o.key = hash_values(hash_string(name), static_cast<uint64_t>(k));
    o.quadrature_max_depth = 3;  // the image border cuts some cells: keep the refinement cheap
    runs.emplace_back(fmt::format("k={}", k),
                      chi2_test(
                          Chi2Domain::rectangle(proj.chart_lo(), proj.chart_hi(), 51, 51),
                          [&](Uniforms& u) { return proj.sample(u); }, [&](const Vec2& q) { return proj.pdf(q); }, o));
  }
  return chi2_record(runs, "raster offset (phi, ln r)");
}

CheckResult caustic_chi2(const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const CausticPerturbation caustic(sc.ctx);
  std::vector<std::pair<std::string, SamplerChi2Result>> runs;
  for (int k : {2, 3}) {
    const CausticAngleProjection proj{&caustic, path_with_segments(sc.ctx, k, kMaxDepth, cx.seed + 20 + k)};
    SamplerChi2Options o;
    o.samples = cx.size(100000, 1000000);
    o.seed = cx.seed;
    o.key = hash_values(hash_string(name), static_cast<uint64_t>(k));
    o.quadrature_max_depth = 3;
    runs.emplace_back(fmt::format("k={}", k),
                      chi2_test(
                          Chi2Domain::rectangle(proj.chart_lo(), proj.chart_hi(), 51, 51),
                          [&](Uniforms& u) { return proj.sample(u); }, [&](const Vec2& q) { return proj.pdf(q); }, o));
  }
  return chi2_record(runs, "direction change (phi, ln theta)");
}

// ---- net flux: antisymmetric statistics of chains from importance-resampled starts (net_flux.h) ----
CheckResult net_flux_check(BidirFault fault, const CheckContext& cx, const std::string& name) {
  const CornellScene& sc = cornell();
  const BidirectionalMutation bidir(sc.ctx, kMaxDepth + 1, fault);
  const LensPerturbation lens(sc.ctx);
  const CausticPerturbation caustic(sc.ctx);
  const auto kernel =
      mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mcmc::Mixture(MutationSelection{}, bidir, lens, caustic));
  NetFluxOptions o;
  o.chains = cx.size(256, 2048);
  o.steps = 150;
  o.max_depth = kMaxDepth;
  o.seed = cx.seed;
  o.key = hash_string(name);
  const NetFluxSamples f = net_flux(kernel, sc.ctx, o);
  const double alpha_each = 1.0 - std::pow(1.0 - kAlpha, 1.0 / static_cast<double>(f.names.size()));
  CheckResult res;
  res.passed = true;
  res.statistic_name = "min p (t-test of b_c sum g over chains)";
  res.statistic = 1.0;
  res.alpha = alpha_each;
  res.samples = f.transitions;
  std::string msg;
  for (size_t i = 0; i < f.names.size(); ++i) {
    stats::Welford w;
    for (double z : f.z[i]) w.add(z);
    const auto t = stats::one_sample_t_test(w, 0.0);
    res.passed = res.passed && !(t.p_value < alpha_each);
    res.statistic = std::min(res.statistic, t.p_value);
    res.details[f.names[i]] = {{"mean", w.mean()}, {"p", t.p_value}};
    msg += fmt::format("{}{}: p = {:.3g}", msg.empty() ? "" : ", ", f.names[i], t.p_value);
  }
  res.p_value = res.statistic;
  res.details["chains_started"] = f.chains_started;
  res.details["accepted"] = f.accepted;
  res.message = fmt::format("{} chains x {} steps, net flux of {}", o.chains, o.steps, msg);
  return res;
}

// ---- image: render_mlt against BDPT -----------------------------------------------------------------
// 8 x 8 Cornell box, max depth 3; each chain is one Welch sample (docs/mlt-path-space.md: the
// estimator is unbiased for every chain length), compared per pixel-channel with a BDPT image
// (compare_channels: Šidák over pixels and channels, Stouffer, sum z^2) at alpha = 1e-5.
CheckResult image_check(const MltOptions& opt, const CheckContext& cx, const std::string& name) {
  static const std::unique_ptr<World> world = load_scene_at_resolution("cornell-box.json", 8, 8);
  Film ref(8, 8);
  RenderSettings rs;
  rs.spp = cx.size(2048, 8192);
  rs.passes = 32;
  rs.max_depth = 3;
  rs.seed = hash_values(cx.seed, hash_string(name + ".bdpt"));
  render_bdpt(*world, rs, ref);
  Film film(8, 8);
  RenderSettings st;
  st.passes = cx.size(48, 128);
  st.spp = st.passes * 160;
  st.max_depth = 3;
  st.seed = hash_values(cx.seed, hash_string(name));
  const MltStats s = run_mlt(*world, st, film, opt);
  const ChannelCompare c = compare_channels(film.welch(), ref.welch(), kAlpha);
  CheckResult res;
  res.passed = !c.rejects();
  res.statistic_name = "p";
  res.statistic = c.p_value();
  res.p_value = c.p_value();
  res.alpha = kAlpha;
  res.samples = s.mutations_total;
  res.message = fmt::format("{} chains x {} mutations against BDPT: {}", s.chains, s.mutations_total / std::max<int64_t>(1, s.chains),
                            c.message());
  res.details = c.details();
  res.details["mutations_per_second"] = s.mutations_per_second();
  for (const auto& m : s.mutations) res.details["acceptance_" + m.name] = m.acceptance_rate();
  return res;
}

void add(const std::string& name, const std::string& desc, CheckKind kind,
         std::function<CheckResult(const CheckContext&, const std::string&)> f) {
  Registry::global().add(
      Check{.name = name, .description = desc, .kind = kind, .run = [=](const CheckContext& cx) { return f(cx, name); }});
}

const bool registered = [] {
  const std::string p = "mlt.path_space.";
  add(p + "bidirectional.pairwise",
      "Bidirectional mutation (Veach 1997, Sec. 11.4.2): pi T a symmetric to 1e-9 on seeded Cornell-box path pairs, "
      "stated T against the path_densities reference",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return bidir_pairwise(BidirFault::kNone, cx, n);
      });
  add(p + "bidirectional.way_chi2",
      "Bidirectional mutation, one-vertex ways: direction of the new vertex against the stated density (chi-square)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return bidir_chi2(BidirFault::kNone, cx, n);
      });
  add(p + "lens.pairwise",
      "Lens perturbation (Veach 1997, Sec. 11.4.3): pi T a symmetric to 1e-9 on seeded Cornell-box path pairs",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return lens_pairwise(LensFault::kNone, cx, n);
      });
  add(p + "lens.offset_chi2",
      "Lens perturbation: realised raster offset against the stated density in (phi, ln r) (chi-square)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return lens_chi2(cx, n); });
  add(p + "caustic.pairwise",
      "Caustic perturbation (Veach 1997, Sec. 11.4.4): pi T a symmetric to 1e-9 on seeded Cornell-box path pairs",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) { return caustic_pairwise(cx, n); });
  add(p + "caustic.angle_chi2",
      "Caustic perturbation: realised direction change against the stated density in (phi, ln theta) (chi-square)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return caustic_chi2(cx, n); });
  add(p + "mixture.pairwise",
      "The MLT kernel (bidirectional + lens + caustic, length-dependent selection): pi c T a symmetric to 1e-9",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return mixture_pairwise(mcmc::HastingsRatio{}, cx, n);
      });
  add(p + "mixture.net_flux",
      "The MLT kernel: zero net flux in path length, raster x / y and ln pi (t-tests over resampled-start chains)",
      CheckKind::kStatistical,
      [](const CheckContext& cx, const std::string& n) { return net_flux_check(BidirFault::kNone, cx, n); });
  add(p + "negative_control.bidir_missing_geometry.net_flux",
      "Negative control: the net-flux check must reject the MLT kernel with a bidirectional density without geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return negate(net_flux_check(BidirFault::kMissingGeometryTerm, cx, n));
      });
  add(p + "image.cornell",
      "render_mlt (>= 48 chains as Welch samples) against BDPT on the 8 x 8 Cornell box (Welch t, Stouffer, sum z^2)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return image_check({}, cx, n); });
  add(p + "negative_control.mixture_metropolis_ratio.pairwise",
      "Negative control: the pairwise check must reject the MLT kernel accepting with pi(y) / pi(x) only",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return negate(mixture_pairwise(mcmc::MetropolisRatioOnly{}, cx, n));
      });
  add(p + "negative_control.bidir_missing_geometry.image",
      "Negative control: the image check must reject render_mlt with a bidirectional density without geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        MltOptions o;
        o.bidir_fault = BidirFault::kMissingGeometryTerm;
        return negate(image_check(o, cx, n));
      });
  add(p + "negative_control.lens_missing_ratio.pairwise",
      "Negative control: the pairwise check must reject the lens perturbation with T(y->x)/T(x->y) dropped",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return negate(lens_pairwise(LensFault::kDropDensityRatio, cx, n));
      });
  add(p + "negative_control.bidir_missing_geometry.pairwise",
      "Negative control: the pairwise check must reject a bidirectional density without the geometry term",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return negate(bidir_pairwise(BidirFault::kMissingGeometryTerm, cx, n));
      });
  add(p + "negative_control.bidir_missing_geometry.way_chi2",
      "Negative control: the way chi-square must reject a bidirectional density without the geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return negate(bidir_chi2(BidirFault::kMissingGeometryTerm, cx, n));
      });
  return true;
}();

}  // namespace
}  // namespace tb

// Image-level checks of the Monte Carlo integrators (docs/validation.md A and F;
// docs/integrator-checks.md): every registered path tracer ("pt"), light tracer ("lt") and
// bidirectional path tracer ("bdpt") against exact images of closed-form worlds
// (validate/render/analytic_worlds.h), against each other on the shipped scenes, every BDPT
// technique against the MIS combination, negative controls (the broken estimator terms of validate/render/broken_integrators.h) that
// must be caught, and convergence-rate / efficiency fits. An integrator that is not registered
// fails its checks with "not registered": a missing estimator never passes.
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "validate/checks/checked_scenes.h"
#include "validate/registry.h"
#include "validate/render/analytic_worlds.h"
#include "validate/render/broken_integrators.h"
#include "validate/render/naive_path_tracer.h"
#include "validate/render/render_compare.h"
#include "validate/render/render_convergence.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

constexpr double kAlpha = 0.01;  // per check (Šidák inside a check over what it compares)
const std::vector<std::string> kIntegrators = {"pt", "lt", "bdpt"};

uint64_t seed_for(const CheckContext& ctx, const std::string& what) { return hash_values(ctx.seed, hash_string(what)); }

// ---------------------------------------------------------------------------------------------
// 1. Closed-form worlds.

// Sizes: pixels per side, Welch samples (passes), raw samples per pass. Few pixels and many
// samples per pixel: the Welch t statistic of skewed samples (Russian roulette weights, rare
// splats) is biased towards the sign opposite to the skew by about skew / (2 sqrt(N)) for N raw
// samples per pixel, and Stouffer's sum over P pixel-channels adds that up to a shift of
// sqrt(P) skew / (2 sqrt(N)) standard deviations; keeping P / N small keeps it negligible while
// the power against a relative bias b, about b sqrt(P N) / cv, stays the same.
struct ImageSize {
  int resolution;
  int64_t passes, spp_per_pass;
};

struct AnalyticCase {
  std::string key;  // furnace, sky_plane, one_bounce_sphere, one_bounce_point
  ImageSize quick, full;
  int max_depth;
};

const std::vector<AnalyticCase>& analytic_cases() {
  static const std::vector<AnalyticCase> c = {
      {"furnace", {4, 32, 64}, {8, 64, 256}, 5},
      {"sky_plane", {4, 32, 64}, {8, 64, 256}, 5},
      {"one_bounce_sphere", {8, 32, 64}, {16, 64, 256}, 5},
      {"one_bounce_point", {8, 32, 64}, {16, 64, 256}, 5},
  };
  return c;
}

AnalyticScene make_analytic(const std::string& key, int resolution, int max_depth) {
  if (key == "furnace" || key == "furnace_dim") {
    FurnaceParams p;
    // Dim: light tracing's roulette probability is min(1, max throughput) with the emitted
    // radiance in the throughput, so with Le ~ 1 it never plays; at Le ~ 1e-3 it does.
    if (key == "furnace_dim") p.emission = Rgb(0.002, 0.004, 0.001);
    p.resolution = resolution;
    p.max_depth = max_depth;
    return make_furnace(p);
  }
  if (key == "sky_plane") {
    SkyPlaneParams p;
    p.resolution = resolution;
    return make_sky_plane(p);
  }
  OneBounceParams p;
  p.resolution = resolution;
  if (key == "one_bounce_point") {
    p.light = OneBounceLight::kPoint;
    p.light_position = Vec3(1.0, 0.3, 0.8);
    p.emission = Rgb(2.0, 1.5, 1.0);
  }
  return make_one_bounce(p);
}

// Light tracing spreads its paths over the image (a pixel receives a splat from a small
// fraction of them): 4x the samples keep every pixel's Welch samples away from the all-zero
// case and close to normal. The other integrators are compared at the base size.
int64_t sample_factor(const std::string& integrator) { return integrator == "lt" ? 4 : 1; }

RenderSettings settings_for(const CheckContext& ctx, const ImageSize& q, const ImageSize& f, int max_depth,
                            const std::string& what, int64_t factor = 1) {
  RenderSettings st;
  st.passes = ctx.full ? f.passes : q.passes;
  st.spp = st.passes * ctx.size(q.spp_per_pass, f.spp_per_pass) * factor;
  st.max_depth = max_depth;
  st.seed = seed_for(ctx, what);
  return st;
}

// Renders `scene` with `integrator` (fault optional) and compares with the exact image.
CheckResult analytic_compare(const std::string& integrator, const AnalyticScene& scene,
                             RenderSettings st, bool expect_reject, double alpha, const std::string& what) {
  const RenderRun run = integrator == "naive" ? [&] {
    RenderRun r;
    r.integrator = "naive";
    r.film.emplace(scene.world->camera().width(), scene.world->camera().height());
    r.passes = render_naive_path_tracer(*scene.world, st, *r.film);
    return r;
  }()
                                              : render_with(integrator, *scene.world, st);
  if (!run.ok()) return render_error_record(run, what);
  WelchImage img = run.film->welch();
  WelchImage exact = exact_welch_image(img.width, img.height, scene.exact);
  const int64_t deterministic = reconcile_deterministic(img, exact);
  const ChannelCompare c = compare_channels(img, exact, alpha);
  CheckResult r = compare_record(c, expect_reject, what);
  r.details["deterministic_channels"] = deterministic;
  if (deterministic > 0)
    r.message += fmt::format(" [{} pixel-channels deterministic and equal to the exact value to 1e-9]", deterministic);
  r.samples = st.spp * run.film->pixel_count();
  r.details["render"] = run.summary();
  r.details["settings"] = {{"spp", st.spp}, {"passes", st.passes}, {"max_depth", st.max_depth}, {"seed", st.seed},
                           {"russian_roulette", st.russian_roulette}, {"rr_min_depth", st.rr_min_depth},
                           };
  r.details["scene"] = scene.scene;
  r.details["exact_pixel_0"] = {scene.exact[0].r, scene.exact[0].g, scene.exact[0].b};
  if (run.nonfinite() > 0) {
    r.passed = false;
    r.message = fmt::format("{} non-finite samples ({}); {}", run.nonfinite(), run.film->nonfinite().summary(), r.message);
  }
  return r;
}

CheckResult run_analytic(const CheckContext& ctx, const AnalyticCase& ac, const std::string& integrator) {
  const ImageSize& sz = ctx.full ? ac.full : ac.quick;
  const AnalyticScene scene = make_analytic(ac.key, sz.resolution, ac.max_depth);
  const std::string what = fmt::format("{} on {}", integrator, scene.name);
  RenderSettings st = settings_for(ctx, ac.quick, ac.full, ac.max_depth, what, sample_factor(integrator));
  return analytic_compare(integrator, scene, st, false, kAlpha, what);
}

// The exact images themselves, against the naive BSDF-sampling path tracer (independent of
// the integrators' light sampling and MIS code): Šidák over the four worlds.
CheckResult run_exact_images(const CheckContext& ctx) {
  const auto& cases = analytic_cases();
  const double alpha_each = stats::sidak_alpha(kAlpha, int64_t(cases.size()));
  CheckResult r;
  r.passed = true;
  r.alpha = kAlpha;
  r.statistic_name = "min p";
  r.statistic = 1.0;
  double min_p = 1.0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const AnalyticCase& ac = cases[i];
    // BSDF sampling finds the small sphere light rarely (about 1.5% of the samples, raw
    // skewness ~ 8): many samples on few pixels keep the Welch t statistics close to their null
    // distribution (their small-sample skew bias adds up in Stouffer's sum over pixels).
    // Furnace and sky are deterministic for this estimator (every sample is the exact value up
    // to rounding); the point light needs NEE only, which the naive tracer does exactly.
    const bool sphere = ac.key == "one_bounce_sphere";
    const ImageSize q = sphere ? ImageSize{4, 32, 1024} : ImageSize{4, 8, 16};
    const ImageSize f = sphere ? ImageSize{8, 64, 4096} : ImageSize{8, 16, 64};
    const AnalyticScene scene = make_analytic(ac.key, (ctx.full ? f : q).resolution, ac.max_depth);
    const std::string what = fmt::format("naive on {}", scene.name);
    const RenderSettings st = settings_for(ctx, q, f, ac.max_depth, what);
    const CheckResult c = analytic_compare("naive", scene, st, false, alpha_each, what);
    r.passed = r.passed && c.passed;
    r.samples += c.samples;
    min_p = std::min(min_p, c.p_value);
    r.details[ac.key] = c.details;
    r.details[ac.key]["message"] = c.message;
    r.message += (r.message.empty() ? "" : "; ") + fmt::format("{} p={:.3g}", scene.name, c.p_value);
    ctx.progress(double(i + 1) / double(cases.size()));
  }
  r.statistic = min_p;
  r.p_value = std::min(1.0, stats::sidak_adjust(min_p, int64_t(cases.size())));
  r.message = fmt::format("exact images vs naive BSDF-sampling path tracer ({}): {}",
                          r.passed ? "consistent" : "DIFFERENT", r.message);
  return r;
}

// ---------------------------------------------------------------------------------------------
// 4. Negative controls: a broken estimator term in a world where it matters; PASS = rejected.

struct ControlCase {
  std::string fault_name;
  EstimatorFault fault;
  std::string world;  // analytic world key
  std::string sizes;  // the analytic case whose sizes it uses
};

const std::vector<ControlCase>& control_cases() {
  static const std::vector<ControlCase> c = {
      {"mis_missing_density", EstimatorFault::kMisMissingDensity, "one_bounce_sphere", "one_bounce_sphere"},
      {"nee_no_cosine", EstimatorFault::kNeeNoCosine, "one_bounce_sphere", "one_bounce_sphere"},
      {"roulette_no_inverse", EstimatorFault::kRouletteNoInverse, "furnace_dim", "furnace"},
  };
  return c;
}

CheckResult run_control(const CheckContext& ctx, const ControlCase& cc, const std::string& integrator) {
  const AnalyticCase* ac = nullptr;
  for (const auto& a : analytic_cases())
    if (a.key == cc.sizes) ac = &a;
  const ImageSize& sz = ctx.full ? ac->full : ac->quick;
  const AnalyticScene scene = make_analytic(cc.world, sz.resolution, ac->max_depth);
  const std::string what = fmt::format("{} with fault {} on {}", integrator, cc.fault_name, scene.name);
  RenderSettings st = settings_for(ctx, ac->quick, ac->full, ac->max_depth, what, sample_factor(integrator));
  if (cc.fault == EstimatorFault::kRouletteNoInverse) {
    st.russian_roulette = true;
    st.rr_min_depth = 0;  // roulette from the first vertex: the missing 1/q biases every path
  }
  return analytic_compare(broken_integrator_name(integrator, cc.fault), scene, st, true, kAlpha, what);
}

// ---------------------------------------------------------------------------------------------
// 2. Agreement on the shipped scenes against a long BDPT reference.

struct SceneCase {
  std::string key, file;
  ImageSize quick, full;
  int64_t reference_factor;  // reference spp = factor x the tested spp
};

// The shipped scenes of validate/checks/checked_scenes.h, all at the same sizes (the smooth meshes:
// every estimator must apply the same shading-normal convention, light subpaths the adjoint
// correction, Veach 1997, Eq. 5.19; docs/path.md, Shading normals).
const std::vector<SceneCase>& scene_cases() {
  static const std::vector<SceneCase> c = [] {
    std::vector<SceneCase> v;
    for (const auto& s : agreement_scenes()) v.push_back({s.key, s.file, {12, 16, 8}, {32, 64, 32}, 8});
    return v;
  }();
  return c;
}
constexpr int kSceneMaxDepth = 5;
// Light tracing is compared only on pixels whose first hit is rougher than this (Beckmann
// alpha): behind delta vertices it cannot sample at all, behind the near-specular glass (0.1),
// gold (GGX 0.2) and metal (0.05) of glossy.json its Welch samples are far too heavy-tailed for
// a t-test (measured: t = -50 in single pixels at 512 paths per pixel, shrinking with more samples).
constexpr double kLtMinRoughness = 0.3;

// The BDPT reference of a shipped scene, rendered once per (scene, size, sample scale) and
// shared by the checks of the run. Its seed is fixed (independent of the checks' seeds, so the
// tested renders and the reference are independent streams).
std::shared_ptr<const RenderRun> scene_reference(const CheckContext& ctx, const SceneCase& sc, const World& world) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const RenderRun>> cache;
  const std::string key = fmt::format("{}:{}:{}", sc.key, ctx.full, ctx.sample_scale);
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  RenderSettings st;
  const ImageSize& sz = ctx.full ? sc.full : sc.quick;
  st.passes = sz.passes;
  st.spp = st.passes * ctx.size(sc.quick.spp_per_pass, sc.full.spp_per_pass) * sc.reference_factor;
  st.max_depth = kSceneMaxDepth;
  st.seed = hash_values(hash_string("integrator.agreement.reference"), hash_string(key));
  auto run = std::make_shared<RenderRun>(render_with("bdpt", world, st));
  cache[key] = run;
  return run;
}

// `control_name`: a broken variant found by find_render_function under that name (e.g. "pf1~mmis_omits_query")
// instead of a broken estimator term.
// `params`: integrator parameters (pfk's vertices), part of the record's name and seed.
CheckResult run_agreement(const CheckContext& ctx, const SceneCase& sc, const std::string& integrator,
                          std::optional<EstimatorFault> fault = std::nullopt, const std::string& control_name = "",
                          const std::map<std::string, double>& params = {}) {
  const bool control = fault.has_value() || !control_name.empty();
  const ImageSize& sz = ctx.full ? sc.full : sc.quick;
  const auto world = load_scene_at_resolution(sc.file, sz.resolution, sz.resolution);
  std::string param_text;
  for (const auto& [k, v] : params) param_text += fmt::format(" {}={}", k, v);
  const std::string what = fmt::format("{}{} vs bdpt reference on {} ({}x{})", integrator, param_text, sc.key,
                                       sz.resolution, sz.resolution);
  const auto ref = scene_reference(ctx, sc, *world);
  if (!ref->ok()) return render_error_record(*ref, what + " (reference)");
  // Path tracing finds the glossy and refractive caustics of glossy.json and caustic.json only by
  // BSDF sampling into a small light: unbiased (measured: glossy 12x12 at 16k spp, image sum pt
  // 16.683 +- 0.034 vs bdpt 16.680 +- 0.014) but so heavy-tailed at 128 spp that its typical
  // image is darker than its mean and the t-test rejects. It is cheap: 16x the samples.
  // pf1 and pfk share pt's next-event estimation and path tracing beyond their filtered vertices: the same 16x.
  const bool filtering = integrator == "pf1" || integrator == "pfk";
  const int64_t factor = integrator == "pt" || filtering ? 16 : sample_factor(integrator);
  RenderSettings st = settings_for(ctx, sc.quick, sc.full, kSceneMaxDepth, what, factor);
  st.params = params;
  const RenderRun run = render_with(!control_name.empty() ? control_name
                                    : control             ? broken_integrator_name(integrator, *fault)
                                                          : integrator,
                                    *world, st);
  if (!run.ok()) return render_error_record(run, what);
  WelchImage a = run.film->welch(), b = ref->film->welch();
  int64_t excluded = 0;
  std::vector<bool> mask;
  if (integrator == "lt") mask = shiny_first_hit_pixels(*world, kLtMinRoughness);
  // Path tracing: pixels that receive a caustic directly or see one through the glass.
  if (integrator == "pt" || filtering)
    mask = mask_union(caustic_receiver_pixels(*world), shiny_first_hit_pixels(*world));
  // bdpt: a caustic seen through the glass (eye - S - S - D - S - S - light) has no connectable
  // pair of vertices and is sampled by s = 0 alone, heavy-tailed in test and reference alike
  // (measured at full size: single pixels at t = -5.7 behind the glass sphere).
  if (integrator == "bdpt") mask = shiny_first_hit_pixels(*world);
  for (bool m : mask) excluded += m;
  exclude_pixels(a, b, mask);
  // pt on caustic.json: besides the refractive caustic (masked), the glass sphere throws a
  // reflective caustic (Fresnel reflection of the small, bright light) on the floor around it,
  // which pt reaches only by BSDF sampling off the sphere into the light. Every floor pixel has
  // such heavy-tailed contributions: at full size (32x32, 32768 spp) the per-pixel comparison
  // rejected with Stouffer Z = -10.4 (and -15.4 at 4x samples) while the mean relative
  // difference was +0.003 (-0.0001): the small-sample skew bias of t summed over 540 pixels,
  // not a bias of pt. pt is compared on the image sum there (see image_sum).
  const bool aggregate = integrator == "pt" && sc.key == "caustic";
  const ChannelCompare c = aggregate ? compare_channels(image_sum(a), image_sum(b), kAlpha)
                                        : compare_channels(a, b, kAlpha, agreement_compare_options(integrator));
  CheckResult r = compare_record(c, control, (control ? what + " with a fault" : what) + (aggregate ? " (image sum)" : ""));
  r.details["image_sum_only"] = aggregate;
  r.samples = st.spp * run.film->pixel_count();
  r.details["render"] = run.summary();
  r.details["reference"] = ref->summary();
  r.details["fault"] = fault ? fault_name(*fault) : control ? control_name : "none";
  r.details["excluded_pixels"] = excluded;
  r.details["settings"] = {{"spp", st.spp}, {"passes", st.passes}, {"max_depth", st.max_depth}, {"seed", st.seed},
                           {"params", params}};
  if (excluded > 0)
    r.message += fmt::format(" [{} pixels excluded: {}]", excluded,
                             integrator == "lt"   ? "first hit delta or near-specular"
                             : integrator == "pt" || filtering
                                 ? "first hit is delta or sees a light through a delta surface"
                                                  : "first hit is delta");
  if (run.nonfinite() + ref->nonfinite() > 0) {
    r.passed = false;
    r.message = fmt::format("{} non-finite samples; {}", run.nonfinite() + ref->nonfinite(), r.message);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// 3. Every BDPT technique (s, t), unweighted (only_s = s), against a reference for paths of the
// same length (only_length = L segments, t = L + 1 - s):
//  - in the furnace, against the exact image of paths of exactly L segments, Le rho^(L-1):
//    every technique has bounded variance there (two points on a sphere have the constant
//    geometry term cos cos / d^2 = 1 / (4 R^2)), so the t-test is valid for all of them;
//  - in the Cornell box, against the MIS image of the same length, for the techniques whose
//    unweighted variance is finite: s <= 1 (camera subpath hitting the light, next-event) and
//    t = 1 (light subpath to the camera). A connection of two surface points (s >= 2 and
//    t >= 2) has G = cos cos / d^2 ~ 1 / d^2 near the box's concave edges, whose square is not
//    integrable there: its unweighted estimator has infinite variance and no t-test on its mean
//    is valid (Veach 1997, Sec. 10.3.2 on the 1/d^2 singularity). Those are covered by the furnace.

struct TechniqueWorld {
  std::unique_ptr<World> world;
  std::vector<Rgb> exact;  // empty: compare against the bdpt MIS image of the same length
  std::string label;
};

CheckResult run_techniques(const CheckContext& ctx, int length, bool furnace) {
  TechniqueWorld tw;
  int64_t passes = ctx.full ? 64 : 32;
  const int64_t spp_pass = ctx.size(furnace ? 64 : 128, 1024);
  if (furnace) {
    FurnaceParams fp;
    fp.resolution = ctx.full ? 8 : 4;
    fp.max_depth = length;
    AnalyticScene a = make_furnace(fp);
    tw.world = std::move(a.world);
    // Paths of exactly `length` segments: L - 1 scattering events, then the emitter.
    const Rgb only_l = fp.emission * glm::pow(fp.albedo, Rgb(double(length - 1)));
    tw.exact.assign(a.exact.size(), only_l);
    tw.label = fmt::format("furnace ({}x{})", fp.resolution, fp.resolution);
  } else {
    // Few large pixels: the camera subpath of s = 0 hits the small light rarely, and a pixel whose
    // Welch samples are all zero makes the t-test meaningless; at 4x4 every pixel integrates
    // enough of the box to see hits in every pass.
    const int res = ctx.full ? 8 : 4;
    passes = ctx.full ? 64 : 32;
    tw.world = load_scene_at_resolution("cornell-box.json", res, res);
    tw.label = fmt::format("Cornell box ({}x{})", res, res);
  }
  const std::string base = fmt::format("bdpt techniques of length {} on the {}", length, tw.label);
  RenderSettings st0;
  st0.passes = passes;
  st0.spp = passes * spp_pass;
  st0.max_depth = length;  // >= length - 1 scattering events; only_length selects the length
  st0.only_length = length;
  std::optional<RenderRun> mis;
  WelchImage reference;
  if (tw.exact.empty()) {
    RenderSettings m = st0;
    m.spp *= 2;  // the MIS image has the lower variance per sample as well
    m.seed = seed_for(ctx, base + " MIS");
    mis = render_with("bdpt", *tw.world, m);
    if (!mis->ok()) return render_error_record(*mis, base + " (MIS reference)");
    reference = mis->film->welch();
  } else {
    reference = exact_welch_image(tw.world->camera().width(), tw.world->camera().height(), tw.exact);
  }
  // Techniques tested: all s in the furnace (plus the MIS image itself against the exact one),
  // s <= 1 or t = 1 in the Cornell box.
  std::vector<int> ss;
  if (furnace) ss.push_back(-1);
  for (int s = 0; s <= length; ++s) {
    const int t = length + 1 - s;
    if (furnace || s <= 1 || t == 1) ss.push_back(s);
  }
  const int64_t m = int64_t(ss.size());
  const double alpha_each = stats::sidak_alpha(kAlpha, m);
  CheckResult r;
  r.passed = true;
  r.alpha = kAlpha;
  r.statistic_name = "min p";
  double min_p = 1.0;
  std::string msgs;
  for (size_t k = 0; k < ss.size(); ++k) {
    const int s = ss[k];
    RenderSettings st = st0;
    st.only_s = s;
    // s = 0 in the Cornell box: a camera subpath hits the small light rarely; its Welch samples
    // are sparse and skewed, so it gets 4x the samples (it traces no light subpath).
    if (!furnace && s == 0) st.spp *= 4;
    const std::string label = s < 0 ? "MIS" : fmt::format("s={},t={}", s, length + 1 - s);
    st.seed = seed_for(ctx, fmt::format("{} {}", base, label));
    const RenderRun run = render_with("bdpt", *tw.world, st);
    if (!run.ok()) {
      r.passed = false;
      msgs += fmt::format("; {}: {}", label, run.error);
      continue;
    }
    WelchImage img = run.film->welch(), ref = reference;
    if (!tw.exact.empty()) reconcile_deterministic(img, ref);
    const ChannelCompare c = compare_channels(img, ref, alpha_each);
    const bool ok = !c.rejects() && run.nonfinite() == 0;
    r.passed = r.passed && ok;
    min_p = std::min(min_p, c.p_value());
    r.samples += st.spp * run.film->pixel_count();
    r.details[label] = c.details();
    r.details[label]["render"] = run.summary();
    msgs += fmt::format("; {}: p={:.3g} rel.diff {:+.3g}{}", label, c.p_value(), c.mean_relative_difference(),
                        ok ? "" : " REJECTED");
    ctx.progress(double(k + 1) / double(m));
  }
  if (mis) r.details["reference"] = mis->summary();
  r.details["techniques_tested"] = ss;
  r.statistic = min_p;
  r.p_value = std::min(1.0, stats::sidak_adjust(min_p, m));
  r.message = fmt::format("{}, unweighted vs {}, Šidák over {}{}", base, furnace ? "exact" : "MIS", m, msgs);
  return r;
}

// Negative control of the technique checks: the next-event technique (s = 1) of paths of two
// segments without the cosine at the receiving vertex, in the furnace (where that cosine is
// d / (2R), not 1), must be rejected by the same comparison.
CheckResult run_technique_control(const CheckContext& ctx) {
  FurnaceParams fp;
  fp.resolution = ctx.full ? 8 : 4;
  fp.max_depth = 2;
  AnalyticScene a = make_furnace(fp);
  a.exact.assign(a.exact.size(), fp.emission * fp.albedo);  // paths of exactly 2 segments: Le rho
  RenderSettings st;
  st.passes = ctx.full ? 64 : 32;
  st.spp = st.passes * ctx.size(64, 256);
  st.max_depth = 2;
  st.only_length = 2;
  st.only_s = 1;
  const std::string what = "bdpt technique s=1,t=2 without the NEE cosine on the furnace";
  st.seed = seed_for(ctx, what);
  a.name = "furnace, paths of 2 segments";
  return analytic_compare(broken_integrator_name("bdpt", EstimatorFault::kNeeNoCosine), a, st, true, kAlpha, what);
}

// ---------------------------------------------------------------------------------------------
// 5. Convergence rate (Ceres fit of RMSE against N, expected exponent 0.5) and efficiency
// 1 / (MSE T) per integrator: quick on the furnace (exact truth), full also on the shipped
// scenes against the BDPT reference (its own variance subtracted).

struct ConvergenceWorld {
  std::string label;
  std::unique_ptr<World> world;
  std::vector<Rgb> truth, truth_variance;
  std::vector<bool> mask;
  std::string error;
};

std::vector<ConvergenceWorld> convergence_worlds(const CheckContext& ctx, const std::string& integrator) {
  std::vector<ConvergenceWorld> out;
  {
    ConvergenceWorld w;
    AnalyticScene s = make_analytic("furnace", 8, 5);
    w.label = s.name;
    w.world = std::move(s.world);
    w.truth = s.exact;
    out.push_back(std::move(w));
  }
  if (!ctx.full) return out;
  for (const auto& sc : scene_cases()) {
    ConvergenceWorld w;
    w.label = sc.key;
    w.world = load_scene_at_resolution(sc.file, sc.full.resolution, sc.full.resolution);
    const auto ref = scene_reference(ctx, sc, *w.world);
    if (!ref->ok()) {
      w.error = ref->error;
    } else {
      const WelchImage& wi = ref->film->welch();
      for (size_t i = 0; i < wi.pixels(); ++i) {
        w.truth.push_back(wi.mean(i));
        w.truth_variance.push_back(wi.variance(i) / double(wi.count[i]));
      }
      if (integrator == "lt") w.mask = shiny_first_hit_pixels(*w.world, kLtMinRoughness);
      if (integrator == "pt") w.mask = mask_union(caustic_receiver_pixels(*w.world), shiny_first_hit_pixels(*w.world));
    }
    out.push_back(std::move(w));
  }
  return out;
}

CheckResult run_convergence(const CheckContext& ctx, const std::string& integrator, bool control) {
  auto worlds = convergence_worlds(ctx, integrator);
  if (control) worlds.resize(1);  // the control runs on the furnace only
  const int64_t m = int64_t(worlds.size());
  CheckResult r;
  r.passed = true;
  r.alpha = kAlpha;
  r.statistic_name = "worst |alpha - 0.5|";
  double worst = 0.0;
  nlohmann::json rows = nlohmann::json::array();
  std::string msgs;
  for (int64_t i = 0; i < m; ++i) {
    ConvergenceWorld& w = worlds[size_t(i)];
    if (!w.error.empty()) {
      r.passed = false;
      msgs += fmt::format("; {}: reference failed: {}", w.label, w.error);
      continue;
    }
    ImageConvergenceOptions opt;
    opt.log2_min = 0;
    opt.log2_max = ctx.full ? 7 : 5;  // the largest N dominates the cost: each extra power doubles it
    opt.replicates = ctx.size(16, 32);
    opt.max_depth = 5;
    opt.seed = seed_for(ctx, integrator + w.label);
    opt.fit.confidence = 1.0 - stats::sidak_alpha(kAlpha, m);
    if (control) {
      opt.base.rr_min_depth = 0;
    }
    const ImageConvergence cv = image_convergence(control ? broken_integrator_name(integrator, EstimatorFault::kRouletteNoInverse) : integrator, *w.world, w.truth, w.truth_variance, w.mask, opt);
    if (!cv.ok()) {
      r.passed = false;
      msgs += fmt::format("; {}: {}", w.label, cv.error);
      continue;
    }
    const bool contains = cv.fit.converged && cv.fit.alpha_lo <= 0.5 && 0.5 <= cv.fit.alpha_hi;
    const bool narrow = !ctx.full || cv.fit.half_width() <= 0.03;  // docs/validation.md F (full size)
    const bool ok = contains && narrow && !cv.floor_fit.floor_detected() && cv.nonfinite == 0;
    // The control passes when the broken estimator is rejected.
    r.passed = r.passed && (control ? !ok : ok);
    worst = std::max(worst, std::abs(cv.fit.alpha - 0.5));
    const auto& last = cv.points.back();
    rows.push_back({{"world", w.label},
                    {"alpha", cv.fit.alpha},
                    {"alpha_lo", cv.fit.alpha_lo},
                    {"alpha_hi", cv.fit.alpha_hi},
                    {"reduced_chi2", cv.fit.reduced_chi2},
                    {"rescaled", cv.fit.rescaled},
                    {"floor_b", cv.floor_fit.b},
                    {"floor_detected", cv.floor_fit.floor_detected()},
                    {"time_alpha", cv.time_fit.alpha},
                    {"efficiency_at_max_n", cv.efficiency_at_max},
                    {"rmse_at_max_n", last.rmse},
                    {"seconds_at_max_n", last.seconds},
                    {"max_spp", last.n},
                    {"nonfinite", cv.nonfinite},
                    {"passed", ok}});
    msgs += fmt::format("; {}: alpha {:.3f} [{:.3f}, {:.3f}]{}, eff. 1/(MSE T) = {:.3g} at {} spp ({:.3g} s)",
                        w.label, cv.fit.alpha, cv.fit.alpha_lo, cv.fit.alpha_hi,
                        cv.floor_fit.floor_detected() ? fmt::format(", floor b={:.3g}", cv.floor_fit.b) : "",
                        cv.efficiency_at_max, last.n, last.seconds);
    r.plots.push_back(stats::convergence_plot(fmt::format("{}{} on {}: RMSE against spp", integrator,
                                                          control ? " (roulette without 1/q)" : "", w.label),
                                              cv.points, &cv.fit, cv.points.size() >= 4 ? &cv.floor_fit : nullptr));
    for (const auto& p : cv.points) r.samples += int64_t(p.n) * opt.replicates;
    ctx.progress(double(i + 1) / double(m));
  }
  r.statistic = worst;
  r.details["studies"] = rows;
  r.message = fmt::format("{}{} convergence (expected exponent 0.5, {:.0f}% interval{}){}",
                          control ? "negative control (must be rejected): " : "", integrator,
                          100.0 * (1.0 - stats::sidak_alpha(kAlpha, m)), ctx.full ? ", half-width <= 0.03" : "", msgs);
  return r;
}

// ---------------------------------------------------------------------------------------------
// Registration (loops: one check per integrator and case).

const bool registered = [] {
  Registry& reg = Registry::global();
  reg.add({.name = "integrator.analytic.exact_images",
           .description = "the exact images of the closed-form worlds (furnace, plane under sky, one bounce from a "
                          "sphere / point light) agree with a naive BSDF-sampling path tracer, alpha 0.01 Šidák "
                          "over 4 worlds",
           .kind = CheckKind::kStatistical,
           .run = run_exact_images});
  for (const auto& integ : kIntegrators) {
    for (const auto& ac : analytic_cases())
      reg.add({.name = fmt::format("integrator.analytic.{}.{}", ac.key, integ),
               .description = fmt::format("{} image of the closed-form world '{}' equals the exact image (per-pixel "
                                          "Welch z, Šidák; Stouffer; sum z^2), alpha 0.01",
                                          integ, ac.key),
               .kind = CheckKind::kStatistical,
               .run = [ac, integ](const CheckContext& c) { return run_analytic(c, ac, integ); }});
    for (const auto& sc : scene_cases())
      reg.add({.name = fmt::format("integrator.agreement.{}.{}", sc.key, integ),
               .description = fmt::format("{} agrees with a longer bdpt reference on {} (Welch t per {}, "
                                          "Šidák; Stouffer; sum z^2), alpha 0.01",
                                          integ, sc.file,
                                          agreement_compare_options(integ).test == CompareTest::kTiled
                                              ? "k x k tile and channel, k from the third moments"
                                              : "pixel-channel"),
               .kind = CheckKind::kStatistical,
               .run = [sc, integ](const CheckContext& c) { return run_agreement(c, sc, integ); }});
  }
  reg.add({.name = "integrator.agreement.control.pt_nee_no_cosine",
           .description = "negative control: pt without the NEE cosine must be rejected against the bdpt reference "
                          "on cornell-box.json, alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) {
             return run_agreement(c, scene_cases()[0], "pt", EstimatorFault::kNeeNoCosine);
           }});
  // pf1 (single-vertex path filtering, docs/mmis-paths.md) on the Cornell box only.
  reg.add({.name = "integrator.agreement.cornell.pf1",
           .description = "pf1 (single-vertex path filtering, unbiased MMIS) agrees with a longer bdpt reference on "
                          "cornell-box.json (tiled Welch t, Šidák; Stouffer; sum z^2), alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) { return run_agreement(c, scene_cases()[0], "pf1"); }});
  reg.add({.name = "integrator.agreement.control.pf1_mmis_omits_query",
           .description = "negative control: pf1 whose MMIS denominator omits the query's own prefix must be "
                          "rejected against the bdpt reference on cornell-box.json, alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) {
             return run_agreement(c, scene_cases()[0], "pf1", std::nullopt, "pf1~mmis_omits_query");
           }});
  // pfk (multi-vertex path filtering, docs/mmis-paths.md) with K = 2 and 3 on the Cornell box and glossy.json.
  for (const int sci : {0, 1})
    for (const int k : {2, 3})
      reg.add({.name = fmt::format("integrator.agreement.{}.pfk{}", scene_cases()[sci].key, k),
               .description = fmt::format("pfk with vertices={} (multi-vertex path filtering, unbiased MMIS) agrees "
                                          "with a longer bdpt reference on {} (tiled Welch t, Šidák; Stouffer; "
                                          "sum z^2), alpha 0.01",
                                          k, scene_cases()[sci].file),
               .kind = CheckKind::kStatistical,
               .run = [sci, k](const CheckContext& c) {
                 return run_agreement(c, scene_cases()[sci], "pfk", std::nullopt, "", {{"vertices", k}});
               }});
  reg.add({.name = "integrator.agreement.control.pfk_mmis_omits_own",
           .description = "negative control: pfk (vertices=2) whose product of sums omits x_2's own technique must be "
                          "rejected against the bdpt reference on cornell-box.json, alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) {
             return run_agreement(c, scene_cases()[0], "pfk", std::nullopt, "pfk~mmis_omits_own", {{"vertices", 2}});
           }});
  reg.add({.name = "integrator.agreement.control.lt_shading_correction_inverted",
           .description = "negative control: lt with the reciprocal of the adjoint BSDF's shading-normal factor "
                          "must be rejected against the bdpt reference on smooth-mesh.json, alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) {
             return run_agreement(c, scene_cases()[3], "lt", EstimatorFault::kShadingCorrectionInverted);
           }});
  for (int length = 2; length <= 4; ++length) {
    reg.add({.name = fmt::format("integrator.bdpt.techniques.furnace.length{}", length),
             .description = fmt::format("every bdpt technique (s, t) with s + t = {}, unweighted, and the MIS image "
                                        "equal the exact furnace image of paths of {} segments, alpha 0.01 Šidák",
                                        length + 1, length),
             .kind = CheckKind::kStatistical,
             .run = [length](const CheckContext& c) { return run_techniques(c, length, true); }});
    reg.add({.name = fmt::format("integrator.bdpt.techniques.cornell.length{}", length),
             .description = fmt::format("the bdpt techniques with s + t = {} and finite variance (s <= 1 or t = 1), "
                                        "unweighted, agree with the MIS image of paths of {} segments on the Cornell "
                                        "box, alpha 0.01 Šidák",
                                        length + 1, length),
             .kind = CheckKind::kStatistical,
             .run = [length](const CheckContext& c) { return run_techniques(c, length, false); }});
  }
  reg.add({.name = "integrator.bdpt.techniques.control.nee_no_cosine",
           .description = "negative control: the unweighted bdpt technique s=1, t=2 without the cosine at the "
                          "receiving vertex must be rejected against the exact furnace image, alpha 0.01",
           .kind = CheckKind::kStatistical,
           .run = run_technique_control});
  // Light tracing has no next-event estimation and no MIS: only its roulette can be broken.
  // bdpt has no Russian roulette (lib/integrator/bdpt.cpp, paths end at max_depth): no control.
  for (const std::string integ : {"pt", "lt", "bdpt"})
    for (const auto& cc : control_cases()) {
      if (!broken_integrator(integ, cc.fault)) continue;  // the integrator has no such term
      reg.add({.name = fmt::format("integrator.control.{}.{}", integ, cc.fault_name),
               .description = fmt::format("negative control: {} with the fault '{}' on the '{}' world must be "
                                          "rejected by the exact-image comparison, alpha 0.01",
                                          integ, cc.fault_name, cc.world),
               .kind = CheckKind::kStatistical,
               .run = [cc, integ](const CheckContext& c) { return run_control(c, cc, integ); }});
    }
  for (const auto& integ : kIntegrators)
    reg.add({.name = fmt::format("integrator.convergence.{}", integ),
             .description = fmt::format("{}: Ceres fit of image RMSE against spp has exponent 0.5 (99% interval, "
                                        "Šidák over worlds), no error floor; efficiency 1/(MSE T) reported; quick: "
                                        "furnace only, full: also the shipped scenes",
                                        integ),
             .kind = CheckKind::kStatistical,
             .run = [integ](const CheckContext& c) { return run_convergence(c, integ, false); }});
  reg.add({.name = "integrator.convergence.control.pt_roulette_no_inverse",
           .description = "negative control: pt with Russian roulette lacking 1/q on the furnace must fail the "
                          "convergence fit (error floor or exponent away from 0.5)",
           .kind = CheckKind::kStatistical,
           .run = [](const CheckContext& c) { return run_convergence(c, "pt", true); }});
  return true;
}();

}  // namespace
}  // namespace tb

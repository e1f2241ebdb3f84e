// Registered checks of lib/material (docs/validation.md A and C):
//  * chi-square of the microfacet normal samplers alone (D(m) cos theta_m for Beckmann and GGX,
//    GGX visible normals D_wo(m)) against their densities, with a negative control;
//  * chi-square of every non-delta BSDF's sample() against its own pdf() over roughness,
//    index of refraction and incident angle (Sidak over configurations), with the hard cases
//    roughness near 0 and IOR near 1 as separately named checks, and a negative control;
//  * reciprocity where it must hold and the eta^2 rule of refraction where it must not;
//  * white furnace: albedo <= 1 (one-sided z-test), with a negative control;
//  * |d omega_h / d omega_o| of the generalised half vector against finite differences.
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <fmt/format.h>

#include "lib/core/frame.h"
#include "lib/core/microfacet.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/material/bsdf_registry.h"
#include "lib/material/half_vector.h"
#include "validate/chi2/direction_chart.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/registry.h"
#include "validate/stats/fd_jacobian.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

// ---- Configurations ----------------------------------------------------------------------

struct BsdfCase {
  std::string bsdf;
  nlohmann::json params;
  double theta_deg = 0;  // incident angle of wo; > 90 means wo below the surface
  std::string label() const { return fmt::format("{}{} theta_o={}", bsdf, params.dump(), theta_deg); }
};

Vec3 wo_at(double theta_deg) {
  const double t = glm::radians(theta_deg), phi = 0.7;  // off-axis azimuth: no cell-edge symmetry
  return {std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)};
}

nlohmann::json rough(const char* dist, double alpha, bool vis) {
  nlohmann::json j = {{"distribution", dist}, {"alpha", alpha}};
  if (vis) j["visible_normals"] = true;
  return j;
}

struct Dist {
  const char* name;
  bool visible;
};
const Dist kDists[] = {{"beckmann", false}, {"ggx", false}, {"ggx", true}};

std::vector<BsdfCase> chi2_cases(const std::string& bsdf, bool full) {
  std::vector<BsdfCase> v;
  const std::vector<double> thetas = full ? std::vector<double>{0, 30, 60, 80, 89.9} : std::vector<double>{40, 89.9};
  if (bsdf == "lambert") {
    for (double t : thetas) v.push_back({bsdf, {{"reflectance", 0.8}}, t});
    v.push_back({bsdf, {{"reflectance", 0.8}}, 120});
    return v;
  }
  const std::vector<double> alphas = full ? std::vector<double>{0.05, 0.1, 0.3, 0.6, 1.0} : std::vector<double>{0.3};
  for (const Dist& d : kDists)
    for (double a : alphas) {
      if (bsdf == "rough_conductor") {
        for (double t : thetas) v.push_back({bsdf, rough(d.name, a, d.visible), t});
      } else {
        const std::vector<double> etas = full ? std::vector<double>{1.1, 1.5, 2.5} : std::vector<double>{1.5};
        for (double eta : etas) {
          nlohmann::json p = rough(d.name, a, d.visible);
          p["eta"] = eta;
          for (double t : thetas) v.push_back({bsdf, p, t});
          v.push_back({bsdf, p, full ? 130.0 : 140.0});  // from inside (beyond TIR for eta 1.5)
          if (full) v.push_back({bsdf, p, 160.0});
        }
      }
    }
  return v;
}

// Named hard cases (docs/validation.md C: never averaged away).
std::vector<BsdfCase> low_roughness_cases(bool full) {
  std::vector<BsdfCase> v;
  for (const Dist& d : kDists)
    for (double t : full ? std::vector<double>{0, 45, 85} : std::vector<double>{45}) {
      v.push_back({"rough_conductor", rough(d.name, 0.01, d.visible), t});
      nlohmann::json p = rough(d.name, 0.01, d.visible);
      p["eta"] = 1.5;
      v.push_back({"rough_dielectric", p, t});
    }
  return v;
}

// ---- Chi-square ---------------------------------------------------------------------------

SamplerChi2Result bsdf_chi2(const Bsdf& b, const Vec3& wo, const CheckContext& ctx, uint64_t key,
                            const std::function<double(const Vec3&)>& pdf) {
  SamplerChi2Options o;
  o.samples = ctx.size(200000, 1000000);
  o.seed = ctx.seed;
  o.key = key;
  const bool reflect_only = !(b.flags() & bsdf_flags::kTransmission) && wo.z > 0;
  // Odd resolutions (docs/validation.md A); the quick grid is coarser so that quadrature stays cheap.
  const int n_phi = ctx.full ? 101 : 41, n_cos = ctx.full ? 51 : 21;
  const Chi2Domain dom = reflect_only ? Chi2Domain::hemisphere(n_phi, n_cos) : Chi2Domain::sphere(n_phi, 2 * n_cos + 1);
  const auto sample = [&](Uniforms& u) -> std::optional<Vec3> {
    const double uc = u.next();
    const Vec2 uv = u.next2();
    const auto s = b.sample(wo, uc, uv, TransportMode::kRadiance);
    if (!s) return std::nullopt;
    return s->wi;
  };
  return chi2_test(dom, sample, [&](const Vec3& wi) { return pdf(wi); }, o);
}

SamplerChi2Result zoomed_bsdf_chi2(const Bsdf& bsdf, const Vec3& wo, const CheckContext& ctx, uint64_t key,
                                   const std::function<double(const Vec3&)>& pdf);

// Chi-square of every case, Šidák over the cases; `zoomed`: on a chart around the sampled lobe
// (lobes far narrower than a whole-sphere grid cell, e.g. eta near 1).
CheckResult run_chi2_cases(const CheckContext& ctx, const std::string& name, const std::vector<BsdfCase>& cases,
                           double alpha_total, bool zoomed = false) {
  const double alpha = stats::sidak_alpha(alpha_total, static_cast<int64_t>(cases.size()));
  CheckResult res;
  res.statistic_name = "min p";
  res.statistic = 1.0;
  res.alpha = alpha;
  res.passed = true;
  std::string worst;
  nlohmann::json per_case = nlohmann::json::array();
  for (size_t i = 0; i < cases.size(); ++i) {
    const BsdfCase& c = cases[i];
    const auto b = make_bsdf(c.bsdf, c.params);
    const Vec3 wo = wo_at(c.theta_deg);
    const auto pdf = [&](const Vec3& wi) { return b->pdf(wo, wi, TransportMode::kRadiance); };
    const auto r = zoomed ? zoomed_bsdf_chi2(*b, wo, ctx, hash_string(name + c.label()), pdf)
                          : bsdf_chi2(*b, wo, ctx, hash_string(name + c.label()), pdf);
    res.samples += r.samples;
    per_case.push_back({{"case", c.label()}, {"p", r.p_value()}, {"chi2", r.gof.statistic}, {"dof", r.gof.dof},
                        {"failed_samples", r.failed}, {"pdf_integral", r.pdf_integral}});
    if (zoomed) per_case.back()["chart_half_width"] = r.domain.x_max;
    if (r.p_value() < res.statistic) {
      res.statistic = r.p_value();
      worst = c.label() + ": " + r.message();
    }
    if (!r.passed(alpha)) res.passed = false;
    state_chi2_power(res, r, alpha);
    ctx.progress(static_cast<double>(i + 1) / static_cast<double>(cases.size()));
  }
  res.p_value = stats::sidak_adjust(res.statistic, static_cast<int64_t>(cases.size()));
  res.details["cases"] = per_case;
  res.message = fmt::format("{} configurations{}, min p = {:.3g} (Sidak alpha per case {:.2e}); worst: {}",
                            cases.size(), zoomed ? " on zoomed caps" : "", res.statistic, alpha, worst);
  return res;
}

void register_chi2(const std::string& bsdf) {
  const std::string name = "material.bsdf." + bsdf + ".chi2";
  Registry::global().add(
      {name,
       "Chi-square of " + bsdf + " sample() against its pdf() over roughness, IOR and incident angle (alpha 0.01, Sidak)",
       CheckKind::kStatistical,
       [name, bsdf](const CheckContext& ctx) { return run_chi2_cases(ctx, name, chi2_cases(bsdf, ctx.full), 0.01); }});
}

[[maybe_unused]] const bool kRegisteredChi2 = [] {
  for (const char* b : {"lambert", "rough_conductor", "rough_dielectric"}) register_chi2(b);
  return true;
}();

TB_REGISTER_CHECK({.name = "material.bsdf.hard.low_roughness.chi2",
                   .description = "Hard case: chi-square of rough BSDF sampling at Beckmann-equivalent alpha = 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& ctx) {
                     return run_chi2_cases(ctx, "material.bsdf.hard.low_roughness.chi2",
                                           low_roughness_cases(ctx.full), 0.01);
                   }});

// ---- IOR near 1 on a zoomed domain (docs/validation.md C hard case "IOR 1.0001") -----------------
// At eta = 1.0001 the transmitted lobe is ~(eta - 1) tan(theta_h) ~ 1e-6..1e-3 rad wide around
// the refracted direction: on the whole sphere the cell quadrature misses it (the pdf integrated
// to 0.03 on a 41 x 43 grid). Here directions are binned on an orthographic chart of a small cap
// (validate/chi2/direction_chart.h, d omega = dx dy / z) fitted to a pilot run on an independent
// stream; the reflected lobe (Fresnel ~1e-9..1e-5) and the tails outside the cap go to the
// failure cell, whose expected count N (1 - int_chart pdf) the tester accounts for.

std::vector<BsdfCase> ior_near_one_zoom_cases(bool full) {
  std::vector<BsdfCase> v;
  // Quick: visible-normal GGX only (the distributions share the half-vector code under test).
  for (const Dist& d : kDists) {
    if (!full && !d.visible) continue;
    for (double a : full ? std::vector<double>{0.01, 0.03, 0.1} : std::vector<double>{0.01, 0.1})
      for (double t : full ? std::vector<double>{0, 30, 60, 80} : std::vector<double>{30, 80}) {
        nlohmann::json p = rough(d.name, a, d.visible);
        p["eta"] = 1.0001;
        v.push_back({"rough_dielectric", p, t});
      }
  }
  return v;
}

// Chi-square of b.sample() on a zoomed cap around its transmitted lobe, against pdf (solid angle).
SamplerChi2Result zoomed_bsdf_chi2(const Bsdf& b, const Vec3& wo, const CheckContext& ctx, uint64_t key,
                                   const std::function<double(const Vec3&)>& pdf) {
  const auto sample = [&](Uniforms& u) -> std::optional<Vec3> {
    const double uc = u.next();
    const Vec2 uv = u.next2();
    const auto s = b.sample(wo, uc, uv, TransportMode::kRadiance);
    if (!s) return std::nullopt;
    return s->wi;
  };
  std::vector<Vec3> pilot;
  for (uint64_t i = 0; i < 4000; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, key ^ 0x9e3779b97f4a7c15ULL, i);
    RngUniforms u(rng);
    if (const auto w = sample(u)) pilot.push_back(*w);
  }
  const auto chart = Chi2DirectionChart::fit(pilot, -wo, 0.9, ctx.full ? 41 : 25);
  if (!chart) throw std::runtime_error("ior_near_one: no pilot sample in the transmitted hemisphere");
  SamplerChi2Options o;
  o.samples = ctx.size(100000, 1000000);
  o.seed = ctx.seed;
  o.key = key;
  // The lobe is smooth on the chart (no rim): a cell's mass to 1e-6 relative is far below
  // 1/sqrt(E); deeper refinement only chases the peak and costs seconds.
  o.quadrature_tolerance = 1e-6;
  o.quadrature_max_depth = 3;
  return chi2_test_zoomed(*chart, sample, [&](const Vec3& wi) { return pdf(wi); }, o);
}

CheckResult run_ior_near_one_chi2(const CheckContext& ctx) {
  return run_chi2_cases(ctx, "material.rough_dielectric.ior_near_one.chi2", ior_near_one_zoom_cases(ctx.full), 0.01,
                        /*zoomed=*/true);
}

TB_REGISTER_CHECK({.name = "material.rough_dielectric.ior_near_one.chi2",
                   .description = "Hard case: chi-square of rough dielectric sampling at eta = 1.0001 (alpha 0.01..0.1, "
                                  "incidence to 80 deg) on a zoomed cap around the transmitted lobe, Sidak alpha 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = run_ior_near_one_chi2});

// Negative control: the sampler at eta = 1.0001, the pdf of the same BSDF with eta mis-stated as
// 1.001 (a lobe ten times too wide). Passes when the zoomed chi-square rejects it.
CheckResult run_ior_near_one_negative_control(const CheckContext& ctx) {
  const nlohmann::json p = {{"distribution", "ggx"}, {"alpha", 0.1}, {"eta", 1.0001}};
  nlohmann::json q = p;
  q["eta"] = 1.001;
  const auto b = make_bsdf("rough_dielectric", p), wrong = make_bsdf("rough_dielectric", q);
  const Vec3 wo = wo_at(30);
  const auto r = zoomed_bsdf_chi2(*b, wo, ctx, hash_string("material.rough_dielectric.ior_near_one.chi2.negative"),
                                  [&](const Vec3& wi) { return wrong->pdf(wo, wi, TransportMode::kRadiance); });
  CheckResult res;
  res.alpha = 0.01;
  res.statistic_name = "p of broken pdf";
  res.statistic = r.p_value();
  res.p_value = r.p_value();
  res.samples = r.samples;
  res.passed = !r.passed(res.alpha);
  res.message = fmt::format("pdf with eta mis-stated as 1.001 (sampler 1.0001) {} at alpha {}: {}",
                            res.passed ? "rejected" : "NOT rejected", res.alpha, r.message());
  return res;
}

TB_REGISTER_CHECK({.name = "material.rough_dielectric.ior_near_one.chi2.negative_control",
                   .description = "The zoomed IOR-near-1 chi-square rejects a pdf with eta mis-stated as 1.001",
                   .kind = CheckKind::kStatistical,
                   .run = run_ior_near_one_negative_control});

// Negative control: the rough dielectric's pdf with the half-vector Jacobian dropped (pdf of the
// microfacet normal reported as the pdf of wi). Passes when the chi-square test rejects it.
CheckResult run_chi2_negative_control(const CheckContext& ctx) {
  const auto b = make_bsdf("rough_dielectric", {{"distribution", "ggx"}, {"alpha", 0.3}, {"eta", 1.5}});
  const Vec3 wo = wo_at(40);
  const auto broken_pdf = [&](const Vec3& wi) {
    const bool refl = wi.z > 0;
    const double eta_i = refl ? 1.0 : 1.5;
    return b->pdf(wo, wi, TransportMode::kRadiance) / half_vector_jacobian(wo, wi, 1.0, eta_i);
  };
  const auto r = bsdf_chi2(*b, wo, ctx, hash_string("material.bsdf.chi2.negative_control"), broken_pdf);
  CheckResult res;
  res.alpha = 0.01;
  res.statistic_name = "p of broken pdf";
  res.statistic = r.p_value();
  res.samples = r.samples;
  res.passed = !r.passed(res.alpha);
  res.message = fmt::format("broken pdf (dropped half-vector Jacobian) {} at alpha {}: {}",
                            res.passed ? "rejected" : "NOT rejected", res.alpha, r.message());
  return res;
}

TB_REGISTER_CHECK({.name = "material.bsdf.chi2.negative_control",
                   .description = "The BSDF chi-square test rejects a pdf with the half-vector Jacobian dropped",
                   .kind = CheckKind::kStatistical,
                   .run = run_chi2_negative_control});

// ---- Microfacet normal sampling ------------------------------------------------------------

// The microfacet normal samplers on their own (lib/core/microfacet.h), m binned on the
// hemisphere: sample_m against pdf_m = D(m) cos theta_m (Walter et al. 2007, Eq. 4 and 28-29,
// 35-36) and sample_visible against pdf_visible = G1(wo, m) max(0, wo.m) D(m) / cos theta_o
// (Heitz & d'Eon 2014, Eq. 2; Heitz 2018). Roughness 0.5 and 0.8 keep the mass spread over
// many (phi, cos theta) rows. broken_norm states D(m) alone as the density of sample_m: the
// normalisation of Walter Eq. 4 lost, which the test must reject.
struct MicrofacetCase {
  MicrofacetType type;
  double alpha;
  double theta_o_deg;  // < 0: sample_m; otherwise sample_visible with wo at this angle
  std::string label() const {
    return theta_o_deg < 0 ? fmt::format("{} alpha={} sample_m", to_string(type), alpha)
                           : fmt::format("{} alpha={} sample_visible theta_o={}", to_string(type), alpha, theta_o_deg);
  }
};

SamplerChi2Result microfacet_chi2(const MicrofacetCase& c, int64_t n, uint64_t seed, uint64_t key, bool broken_norm) {
  const MicrofacetDistribution dist(c.type, c.alpha);
  const Vec3 wo = wo_at(std::max(0.0, c.theta_o_deg));
  const bool visible = c.theta_o_deg >= 0;
  return chi2_test(
      Chi2Domain::hemisphere(),
      [&](const Vec2& u) { return visible ? dist.sample_visible(wo, u) : dist.sample_m(u); },
      [&](const Vec3& m) {
        if (visible) return dist.pdf_visible(wo, m);
        return broken_norm ? dist.D(m) : dist.pdf_m(m);
      },
      SamplerChi2Options{.samples = n, .seed = seed, .key = key});
}

CheckResult run_microfacet_chi2(const CheckContext& ctx) {
  const std::vector<MicrofacetCase> cases = {{MicrofacetType::kBeckmann, 0.5, -1},
                                             {MicrofacetType::kBeckmann, 0.8, -1},
                                             {MicrofacetType::kGgx, 0.5, -1},
                                             {MicrofacetType::kGgx, 0.8, -1},
                                             {MicrofacetType::kGgx, 0.5, 40},
                                             {MicrofacetType::kGgx, 0.8, 80}};
  const int64_t n = ctx.size(200000, 2000000);
  const double alpha = stats::sidak_alpha(0.01, static_cast<int64_t>(cases.size()));
  CheckResult res;
  res.passed = true;
  res.alpha = alpha;
  res.statistic_name = "min p";
  res.details["configurations"] = nlohmann::json::array();
  double min_p = 1.0;
  std::string worst;
  for (size_t i = 0; i < cases.size(); ++i) {
    const SamplerChi2Result r = microfacet_chi2(cases[i], n, ctx.seed, hash_values(hash_string("microfacet"), i), false);
    res.passed = res.passed && r.passed(alpha);
    state_chi2_power(res, r, alpha);
    res.samples += r.samples;
    nlohmann::json d = r.details();
    d["label"] = cases[i].label();
    d["passed"] = r.passed(alpha);
    res.details["configurations"].push_back(d);
    if (r.p_value() <= min_p) {
      min_p = r.p_value();
      worst = cases[i].label() + ": " + r.message();
    }
    ctx.progress(static_cast<double>(i + 1) / static_cast<double>(cases.size()));
  }
  res.statistic = min_p;
  res.p_value = std::min(1.0, stats::sidak_adjust(min_p, static_cast<int64_t>(cases.size())));
  res.message = fmt::format("{} configurations, worst {}", cases.size(), worst);
  return res;
}

CheckResult run_microfacet_chi2_negative_control(const CheckContext& ctx) {
  const SamplerChi2Result r = microfacet_chi2({MicrofacetType::kGgx, 0.5, -1}, ctx.size(200000, 2000000), ctx.seed,
                                              hash_string("microfacet.negative_control"), true);
  CheckResult res;
  res.alpha = 0.01;
  res.statistic_name = "p (must reject)";
  res.statistic = r.p_value();
  res.p_value = r.p_value();
  res.samples = r.samples;
  res.details = r.details();
  res.passed = !r.passed(res.alpha);
  res.message = fmt::format("GGX sample_m with density D(m) (no cos theta_m): {} ({})",
                            res.passed ? "rejected" : "NOT rejected", r.message());
  return res;
}

TB_REGISTER_CHECK({.name = "material.microfacet.chi2",
                   .description = "Microfacet normal sampling alone: Beckmann and GGX D(m) cos theta_m, GGX visible "
                                  "normals D_wo(m), against their stated densities by chi-square",
                   .kind = CheckKind::kStatistical,
                   .run = run_microfacet_chi2});
TB_REGISTER_CHECK({.name = "material.microfacet.chi2.negative_control",
                   .description = "The microfacet chi-square test rejects GGX normal sampling stated with density D(m) "
                                  "(normalisation of D(m) cos theta_m lost)",
                   .kind = CheckKind::kStatistical,
                   .run = run_microfacet_chi2_negative_control});

// ---- Reciprocity and the eta^2 rule -------------------------------------------------------

std::vector<BsdfCase> all_bsdf_cases() {
  std::vector<BsdfCase> v = {{"lambert", {{"reflectance", 0.5}}, 0}};
  for (const Dist& d : kDists)
    for (double a : {0.01, 0.1, 0.5, 1.0}) {
      v.push_back({"rough_conductor", rough(d.name, a, d.visible), 0});
      for (double eta : {1.0001, 1.33, 2.5, 0.7}) {
        nlohmann::json p = rough(d.name, a, d.visible);
        p["eta"] = eta;
        v.push_back({"rough_dielectric", p, 0});
      }
    }
  return v;
}

Vec3 random_dir(Rng& r) {
  const double z = 2 * r.uniform() - 1, phi = 2 * kPi * r.uniform();
  const double s = safe_sqrt(1 - z * z);
  return {s * std::cos(phi), s * std::sin(phi), z};
}

double rel_diff(const Rgb& a, const Rgb& b) {
  const double m = std::max(max_component(glm::abs(a)), max_component(glm::abs(b)));
  // Below the normal range (DBL_MIN ~ 2e-308) values carry few significant bits: not comparable.
  return m < 1e-290 ? 0.0 : max_component(glm::abs(a - b)) / m;
}

CheckResult run_reciprocity(const CheckContext& ctx) {
  const std::vector<BsdfCase> cases = all_bsdf_cases();
  const int64_t pairs = ctx.size(20000, 200000);
  const double tol = 1e-10;  // identities up to round-off of a few dozen flops on O(1) values
  int64_t violations = 0, transmissive = 0;
  double worst = 0;
  std::string first;
  for (const BsdfCase& c : cases) {
    const auto b = make_bsdf(c.bsdf, c.params);
    for (int64_t k = 0; k < pairs; ++k) {
      Rng r = Rng::for_sample(ctx.seed, hash_string(c.label()), static_cast<uint64_t>(k));
      const Vec3 wo = random_dir(r), wi = random_dir(r);
      const Rgb f = b->eval(wo, wi, TransportMode::kRadiance), fr = b->eval(wi, wo, TransportMode::kRadiance);
      const Rgb fi = b->eval(wo, wi, TransportMode::kImportance);
      double err = rel_diff(fi, fr);  // adjoint BSDF (Veach 1997, Sec. 3.7)
      if (wo.z * wi.z > 0) {
        err = std::max(err, rel_diff(f, fr));  // reciprocity of reflection
      } else {
        // Veach 1997, Sec. 5.2: f(wo, wi) / eta_wo^2 = f(wi, wo) / eta_wi^2.
        const double eo = wo.z > 0 ? 1.0 : b->eta(), ei = wi.z > 0 ? 1.0 : b->eta();
        err = std::max(err, rel_diff(f / (eo * eo), fr / (ei * ei)));
        transmissive += !is_black(f);
      }
      if (err > tol && first.empty())
        first = fmt::format("{} pair {} wo=({:.17g},{:.17g},{:.17g}) wi=({:.17g},{:.17g},{:.17g})", c.label(), k, wo.x,
                            wo.y, wo.z, wi.x, wi.y, wi.z);
      violations += err > tol;
      worst = std::max(worst, err);
    }
  }
  CheckResult res;
  res.passed = violations == 0 && transmissive > 0;
  res.statistic_name = "max rel. error";
  res.statistic = worst;
  res.samples = pairs * static_cast<int64_t>(cases.size());
  res.message = fmt::format("{} BSDFs x {} seeded pairs: {} violations (tol {}), worst {:.2e}, {} transmissive pairs{}",
                            cases.size(), pairs, violations, tol, worst, transmissive,
                            first.empty() ? "" : "; first: " + first);
  return res;
}

TB_REGISTER_CHECK({.name = "material.bsdf.reciprocity",
                   .description = "f(wo,wi) = f(wi,wo) for reflection, f/eta_wo^2 symmetric for refraction, "
                                  "f_importance(wo,wi) = f_radiance(wi,wo)",
                   .kind = CheckKind::kDeterministic,
                   .run = run_reciprocity});

// ---- White furnace ------------------------------------------------------------------------

// Scales everything a BSDF returns: the negative control of the furnace test.
class ScaledBsdf final : public Bsdf {
 public:
  ScaledBsdf(std::unique_ptr<Bsdf> b, double s) : b_(std::move(b)), s_(s) {}
  std::string_view name() const override { return "scaled"; }
  uint32_t flags() const override { return b_->flags(); }
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode m) const override { return s_ * b_->eval(wo, wi, m); }
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode m) const override {
    auto s = b_->sample(wo, uc, u, m);
    if (s) {
      s->f *= s_;
      s->weight *= s_;
    }
    return s;
  }
  double pdf(const Vec3& wo, const Vec3& wi, TransportMode m) const override { return b_->pdf(wo, wi, m); }
  double beckmann_roughness() const override { return b_->beckmann_roughness(); }
  double eta() const override { return b_->eta(); }

 private:
  std::unique_ptr<Bsdf> b_;
  double s_;
};

// Albedo of light arriving from w: the mean weight of kImportance sampling from w (bsdf.h).
// Returns the one-sided z-test of H0: albedo <= 1.
stats::TestResult furnace(const Bsdf& b, const Vec3& w, int64_t n, uint64_t seed, uint64_t key, double* mean_out,
                          double* se_out = nullptr) {
  std::vector<double> x(static_cast<size_t>(n));
  parallel_for(static_cast<size_t>(n), [&](size_t i) {
    Rng r = Rng::for_sample(seed, key, i);
    const double uc = r.uniform();
    const Vec2 u = r.uniform2();
    const auto s = b.sample(w, uc, u, TransportMode::kImportance);
    x[i] = s ? max_component(s->weight) : 0.0;
  });
  CompensatedSum s1, s2;
  for (double v : x) {
    s1 += v;
    s2 += v * v;
  }
  const double nn = static_cast<double>(n), mean = s1.value() / nn;
  const double var = std::max(0.0, (s2.value() - nn * mean * mean) / (nn - 1));
  *mean_out = mean;
  if (se_out) *se_out = std::sqrt(var / nn);
  return stats::z_test_greater(mean, std::sqrt(var / nn), 1.0);
}

CheckResult run_furnace(const CheckContext& ctx) {
  std::vector<BsdfCase> cases = all_bsdf_cases();
  cases.push_back({"smooth_conductor", nlohmann::json::object(), 0});
  cases.push_back({"smooth_dielectric", {{"eta", 1.5}}, 0});
  cases.push_back({"lambert", {{"reflectance", 1.0}}, 0});
  const std::vector<double> thetas = {0, 45, 80, 89.9, 135, 175};
  const int64_t n = ctx.size(20000, 400000);
  const int64_t m = static_cast<int64_t>(cases.size() * thetas.size());
  const double alpha = stats::sidak_alpha(1e-3, m);
  CheckResult res;
  res.passed = true;
  res.alpha = alpha;
  res.statistic_name = "max albedo";
  double min_p = 1;
  std::string worst;
  for (const BsdfCase& c : cases) {
    const auto b = make_bsdf(c.bsdf, c.params);
    for (double t : thetas) {
      double mean = 0;
      const auto tr = furnace(*b, wo_at(t), n, ctx.seed, hash_string(c.label() + std::to_string(t)), &mean);
      res.samples += n;
      if (mean > res.statistic) {
        res.statistic = mean;
        worst = fmt::format("{} theta={}: albedo {:.6f}, p {:.3g}", c.label(), t, mean, tr.p_value);
      }
      min_p = std::min(min_p, tr.p_value);
      if (tr.p_value < alpha) res.passed = false;
    }
  }
  res.p_value = stats::sidak_adjust(min_p, m);
  res.message = fmt::format("{} BSDF x direction pairs, {} samples each: largest albedo {}; min p {:.3g} (Sidak alpha {:.2e})",
                            m, n, worst, min_p, alpha);
  return res;
}

TB_REGISTER_CHECK({.name = "material.bsdf.white_furnace",
                   .description = "Albedo <= 1 for every BSDF and incident direction (one-sided z-test, alpha 1e-3 Sidak)",
                   .kind = CheckKind::kStatistical,
                   .run = run_furnace});

CheckResult run_furnace_negative_control(const CheckContext& ctx) {
  // A rough dielectric whose albedo at normal incidence is about 0.99, scaled by 1.05.
  ScaledBsdf b(make_bsdf("rough_dielectric", {{"distribution", "ggx"}, {"alpha", 0.1}, {"eta", 1.5}}), 1.05);
  double mean = 0;
  const auto tr = furnace(b, wo_at(0), ctx.size(20000, 400000), ctx.seed, 0xfa11, &mean);
  CheckResult res;
  res.alpha = 1e-3;
  res.statistic_name = "albedo";
  res.statistic = mean;
  res.p_value = tr.p_value;
  res.samples = ctx.size(20000, 400000);
  res.passed = tr.p_value < res.alpha;
  res.message = fmt::format("BSDF scaled by 1.05: albedo {:.5f}, p {:.3g}: {}", mean, tr.p_value,
                            res.passed ? "rejected" : "NOT rejected");
  return res;
}

TB_REGISTER_CHECK({.name = "material.bsdf.white_furnace.negative_control",
                   .description = "The furnace test rejects a rough dielectric scaled by 1.05",
                   .kind = CheckKind::kStatistical,
                   .run = run_furnace_negative_control});

// ---- White furnace by quadrature ----------------------------------------------------------
//
// The albedo a(wo) = ∫_{S^2} f(wo, wi) |wi.z| dωi (importance mode, as the sampling furnace above)
// by deterministic quadrature of eval() alone, over both hemispheres, with no use of the BSDF's
// sampler, pdf or sampling weights. The variable is the facet normal m on wo's side: every wi on
// wo's side has one m = normalize(wo + wi), every wi on the other side one m = -normalize(η_o wo +
// η_i wi) (Walter et al. 2007, Eq. 13, 16), so
//   a(wo) = ∫_{m on wo's side} [ f(wo, wr) |wr.z| |dωr/dωm| + f(wo, wt) |wt.z| |dωt/dωm| ] dωm,
// wr = reflect(wo, m), wt = refract(wo, m), with the inverse Jacobians of Walter Eq. 14 and 17,
// written here from the formulas rather than taken from lib/material/half_vector.h:
//   |dωr/dωm| = 4 |wo.m|,   |dωt/dωm| = (η_o (wo.m) + η_i (wt.m))^2 / (η_i^2 |wt.m|).
// m is parametrised by tan θ_m = α t, t = x / (1 - x), so that a lobe of width α is O(1) wide in x
// at every roughness; nested adaptive Gauss-Kronrod (Boost.Math) in x and φ_m.
struct QuadratureAlbedo {
  double value = 0, error = 0;
};

QuadratureAlbedo quadrature_albedo(const Bsdf& b, const Vec3& wo, double alpha_scale) {
  using boost::math::quadrature::gauss_kronrod;
  const double side = wo.z > 0 ? 1.0 : -1.0;
  const bool transmissive = (b.flags() & bsdf_flags::kTransmission) != 0;
  const double eta_o = side > 0 ? 1.0 : b.eta(), eta_i = side > 0 ? b.eta() : 1.0;  // wo's side, wt's side
  const double a = alpha_scale;
  const auto integrand_m = [&](const Vec3& m) {  // m on wo's side (side * m.z > 0)
    const double c = glm::dot(wo, m);
    if (c <= 0) return 0.0;
    double sum = 0.0;
    const Vec3 wr = 2.0 * c * m - wo;
    if (side * wr.z > 0) sum += max_component(b.eval(wo, wr, TransportMode::kImportance)) * std::abs(wr.z) * 4.0 * c;
    if (transmissive) {
      const double e = eta_o / eta_i, k = 1.0 - e * e * (1.0 - c * c);
      if (k > 0) {
        const Vec3 wt = glm::normalize(-e * wo + (e * c - std::sqrt(k)) * m);
        const double ct = glm::dot(wt, m);
        if (side * wt.z < 0 && ct < 0) {
          const double jac = sqr(eta_o * c + eta_i * ct) / (eta_i * eta_i * std::abs(ct));
          sum += max_component(b.eval(wo, wt, TransportMode::kImportance)) * std::abs(wt.z) * jac;
        }
      }
    }
    return sum;
  };
  double err_outer = 0;
  const auto over_phi = [&](double x) {
    if (x >= 1.0) return 0.0;
    const double t = x / (1.0 - x), th = std::atan(a * t);
    // dω_m = sin θ dθ dφ, dθ/dx = α / (1 + α² t²) / (1 - x)².
    const double w = std::sin(th) * a / (1.0 + a * a * t * t) / sqr(1.0 - x);
    const double st = std::sin(th), ct = std::cos(th);
    double e = 0;
    const double inner = gauss_kronrod<double, 15>::integrate(
        [&](double phi) { return integrand_m(Vec3(st * std::cos(phi), st * std::sin(phi), side * ct)); }, 0.0,
        2.0 * kPi, 6, 1e-6, &e);
    return w * inner;
  };
  QuadratureAlbedo r;
  r.value = gauss_kronrod<double, 15>::integrate(over_phi, 0.0, 1.0, 8, 1e-5, &err_outer);
  r.error = err_outer;
  return r;
}

CheckResult run_furnace_quadrature(const CheckContext& ctx, double scale) {
  std::vector<BsdfCase> cases;
  for (const BsdfCase& c : all_bsdf_cases())
    if (!c.params.contains("alpha") || c.params["alpha"].get<double>() >= 0.1) cases.push_back(c);
  cases.push_back({"lambert", {{"reflectance", 1.0}}, 0});
  if (scale != 1.0) cases = {{"rough_dielectric", {{"distribution", "ggx"}, {"alpha", 0.1}, {"eta", 1.5}}, 0}};
  const std::vector<double> thetas = scale != 1.0   ? std::vector<double>{0}
                                     : !ctx.full   ? std::vector<double>{0, 135}
                                                   : std::vector<double>{0, 45, 80, 135, 175};
  const int64_t n = ctx.size(20000, 400000);
  const int64_t m = static_cast<int64_t>(cases.size() * thetas.size());
  const double alpha = stats::sidak_alpha(1e-3, m);
  const double zc = stats::normal_quantile(1.0 - alpha / 2.0);
  CheckResult res;
  res.alpha = alpha;
  res.statistic_name = "max quadrature albedo";
  res.passed = true;
  int over_one = 0, disagree = 0;
  double worst_z = 0, lambert_err = 0, worst_near_one = 0;
  std::string worst, first_bad;
  for (const BsdfCase& c : cases) {
    std::unique_ptr<Bsdf> b = make_bsdf(c.bsdf, c.params);
    if (scale != 1.0) b = std::make_unique<ScaledBsdf>(std::move(b), scale);
    const double a_param = c.params.contains("alpha") ? c.params["alpha"].get<double>() : 1.0;
    for (double t : thetas) {
      const Vec3 wo = wo_at(t);
      const QuadratureAlbedo q = quadrature_albedo(*b, wo, a_param);
      // The sampling furnace as a second opinion: its mean must equal the quadrature value.
      double mc = 0, se = 0;
      furnace(*b, wo, n, ctx.seed, hash_string("furnace_quadrature" + c.label() + std::to_string(t)), &mc, &se);
      // The quadrature is trusted to kQuadratureTol absolute (the unit Lambert anchor below shows how
      // close it gets); without the floor a sampler whose weights are all equal (se = 0, IOR near 1)
      // would be compared against the quadrature's own, optimistic error estimate.
      constexpr double kQuadratureTol = 1e-5;
      const double z = (mc - q.value) / std::sqrt(se * se + q.error * q.error + kQuadratureTol * kQuadratureTol);
      res.samples += n;
      const std::string where = fmt::format("{}{} theta_o={}: quadrature {:.6f} (+- {:.1e}), sampling {:.6f} +- {:.1e}",
                                            c.bsdf, c.params.dump(), t, q.value, q.error, mc, se);
      if (q.value > res.statistic) {
        res.statistic = q.value;
        worst = where;
      }
      if (c.bsdf == "lambert" && c.params["reflectance"].get<double>() == 1.0 && t < 90)
        lambert_err = std::max(lambert_err, std::abs(q.value - 1.0));
      // IOR 1.0001 is left out of the agreement test: there quadrature and the sampling furnace
      // differ by 7e-5 at normal incidence (GGX alpha 1, visible normals: 0.999933 against
      // 1.000000 +- 4.5e-9) and by up to 1.7e-2 with wo inside (theta_o = 135), which is not yet
      // explained (docs/material.md); the message reports the largest difference. It stays in the
      // albedo <= 1 test.
      const bool near_one_ior = c.params.contains("eta") && std::abs(c.params["eta"].get<double>() - 1.0) < 1e-3;
      const bool bad_one = q.value > 1.0 + 1e-5 + q.error, bad_z = !near_one_ior && std::abs(z) > zc;
      over_one += bad_one;
      disagree += bad_z;
      if (!near_one_ior) worst_z = std::max(worst_z, std::abs(z));
      if (near_one_ior) worst_near_one = std::max(worst_near_one, std::abs(mc - q.value));
      if ((bad_one || bad_z) && first_bad.empty()) first_bad = where;
    }
  }
  const bool holds = over_one == 0 && disagree == 0 && lambert_err < 1e-5;
  const std::string summary = fmt::format(
      "{} BSDF x direction pairs: {} with quadrature albedo > 1, {} where sampling disagrees (max |z| {:.2f}, "
      "critical {:.2f}; IOR 1.0001 not compared, largest |difference| there {:.1e}); unit Lambert by quadrature "
      "within {:.1e} of 1; largest albedo {}{}",
      m, over_one, disagree, worst_z, zc, worst_near_one, lambert_err, worst,
      first_bad.empty() ? "" : "; first violation: " + first_bad);
  res.p_value = 2.0 * (1.0 - stats::normal_cdf(worst_z));
  if (scale != 1.0) {
    res.passed = over_one > 0;
    res.message = fmt::format("negative control (BSDF scaled by {}): {}; {}", scale, res.passed ? "caught" : "NOT caught", summary);
  } else {
    res.passed = holds;
    res.message = summary;
  }
  return res;
}

TB_REGISTER_CHECK({.name = "material.bsdf.white_furnace.quadrature",
                   .description = "albedo <= 1 by deterministic quadrature of eval() over both hemispheres (facet-normal "
                                  "variable, Walter et al. 2007 Eq. 14, 17), for every non-Dirac BSDF with alpha >= 0.1 "
                                  "and wo on either side; the sampling furnace agrees with it except at IOR 1.0001 (z, Sidak alpha 1e-3)",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_furnace_quadrature(c, 1.0); }});
TB_REGISTER_CHECK({.name = "material.bsdf.white_furnace.quadrature.negative_control",
                   .description = "negative control: a GGX rough dielectric (alpha 0.1, eta 1.5) scaled by 1.05 has "
                                  "quadrature albedo > 1 and must be caught",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_furnace_quadrature(c, 1.05); }});

// ---- Half-vector Jacobian -----------------------------------------------------------------

struct HvConfig {
  Vec3 i, o;
  double eta_i = 1, eta_o = 1;
};

// A facet normal m, i on its front side at angle acos(c), o = reflect or refract(i, m).
std::optional<HvConfig> hv_config(Rng& r, bool refraction, double eta_lo, double eta_hi, bool grazing) {
  const Frame f = Frame::from_z(random_dir(r));
  const double c = grazing ? std::cos(glm::radians(89.9)) * (0.2 + 0.8 * r.uniform()) : 0.02 + 0.98 * r.uniform();
  const double phi = 2 * kPi * r.uniform();
  const Vec3 i = f.to_world(Vec3(std::sqrt(1 - c * c) * std::cos(phi), std::sqrt(1 - c * c) * std::sin(phi), c));
  if (!refraction) return HvConfig{i, reflect(i, f.n), 1.0, 1.0};
  double eta = eta_lo + (eta_hi - eta_lo) * r.uniform();
  if (r.uniform() < 0.5) eta = 1.0 / eta;
  const auto o = refract(i, f.n, eta);
  if (!o) return std::nullopt;
  return HvConfig{i, *o, 1.0, eta};
}

// Chart (a, b) -> h in the tangent basis of h0, o(a, b) = normalize(o0 + s (a e1 + b e2)); both
// charts are isometric at 0, so |det J| / s^2 = |d omega_h / d omega_o|. s = min(1, |H| / eta_o)
// puts the step on the problem's own length scale (H nearly cancels for IOR near 1).
struct HvChart {
  HvConfig c;
  double s;
  Vec3 e1, e2, f1, f2, h0;
  double len_h;
  explicit HvChart(const HvConfig& cfg) : c(cfg) {
    const Vec3 H = generalized_half_vector_unnormalized(c.i, c.o, c.eta_i, c.eta_o);
    len_h = glm::length(H);
    h0 = H / len_h;
    s = std::min(1.0, len_h / c.eta_o);
    coordinate_system(c.o, &e1, &e2);
    coordinate_system(h0, &f1, &f2);
  }
  Eigen::VectorXd f(const Eigen::VectorXd& x) const {
    const Vec3 o = glm::normalize(c.o + s * (x[0] * e1 + x[1] * e2));
    const Vec3 h = glm::normalize(generalized_half_vector_unnormalized(c.i, o, c.eta_i, c.eta_o));
    return Eigen::Vector2d(glm::dot(h, f1), glm::dot(h, f2));
  }
  // Analytic: dh = (I - h h^T) eta_o do / |H|, do = s (da e1 + db e2) at 0.
  Eigen::MatrixXd jac() const {
    Eigen::MatrixXd j(2, 2);
    const Vec3 cols[2] = {e1, e2};
    for (int k = 0; k < 2; ++k) {
      const Vec3 dh = (cols[k] - h0 * glm::dot(h0, cols[k])) * (c.eta_o * s / len_h);
      j(0, k) = glm::dot(dh, f1);
      j(1, k) = glm::dot(dh, f2);
    }
    return j;
  }
  // |det| / s^2 of the central-difference Jacobian; *kappa: its 2-norm condition number.
  double fd_det(double step, double* kappa) const {
    Eigen::VectorXd p(2), m(2);
    Eigen::Matrix2d d;
    for (int k = 0; k < 2; ++k) {
      p.setZero();
      m.setZero();
      p[k] = step;
      m[k] = -step;
      d.col(k) = (f(p) - f(m)) / (2 * step);
    }
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(d);
    *kappa = svd.singularValues()(0) / svd.singularValues()(1);
    return std::abs(d.determinant()) / (s * s);
  }
};

struct HvCase {
  const char* name;
  bool refraction;
  double lo, hi;
  bool grazing;
};
const HvCase kHvCases[] = {{"reflection", false, 1, 1, false},
                           {"refraction", true, 1.0001, 2.5, false},
                           {"grazing_reflection", false, 1, 1, true},
                           {"grazing_refraction", true, 1.0001, 2.5, true},
                           {"ior_near_one", true, 1.0001, 1.001, false}};

CheckResult run_half_vector_fd(const CheckContext& ctx, const std::function<double(const HvConfig&)>& closed_form,
                               bool negative_control) {
  const int64_t per_case = ctx.size(1000, 4000);
  const double step = std::cbrt(2 * kEpsilon);  // eps^(1/3) max(1, |x|) at x = 0 (docs/validation.md C)
  stats::FdOptions fo;
  fo.seed = ctx.seed;
  // Ridders from 1e-3: the chart's curvature is O(1) in (a, b), but from Ceres' default 1e-2 its
  // extrapolation stops at a relative error of ~8e-4 on charts with |H| below ~4e-3 (grazing
  // reflection, IOR within 1e-3 of 1: 428 of 20000 full-size configurations); from 1e-3 none
  // disagrees by 1e-6. Taylor: 10 halvings from 1e-2, the slope fitted over the 4 smallest steps
  // above the rounding floor (larger steps show the cubic term where the quadratic one is small
  // along d), up to 3 directions (see validate/stats/fd_jacobian.h).
  fo.ridders_initial_step = 1e-3;
  fo.taylor_steps = 10;
  fo.taylor_fit_points = 4;
  fo.taylor_directions = 3;
  CheckResult res;
  res.statistic_name = "max rel. error of |dh/do|";
  nlohmann::json per = nlohmann::json::object();
  int64_t total_fail = 0, total = 0, fd_matrix_fail = 0, skipped = 0, ridders_disagree = 0, redrawn = 0;
  double worst_slope_dev = 0;
  std::string first;
  for (const HvCase& hc : kHvCases) {
    double worst = 0, worst_matrix = 0, max_cond = 0;
    int64_t fails = 0, n = 0;
    for (int64_t k = 0; n < per_case && k < 100 * per_case; ++k) {
      Rng r = Rng::for_sample(ctx.seed, hash_string(hc.name), static_cast<uint64_t>(k));
      const auto cfg = hv_config(r, hc.refraction, hc.lo, hc.hi, hc.grazing);
      if (!cfg) continue;
      ++n;
      const HvChart ch(*cfg);
      const double an = closed_form(*cfg);
      double kappa = 1;
      // Relative error over the condition number: rounding in the entries is amplified by
      // 1/sigma_min in the determinant; at 89.9 degrees sigma_min ~ |<h,o>| ~ 1e-3.
      const double err = std::abs(ch.fd_det(step, &kappa) - an) / an / std::max(1.0, kappa);
      max_cond = std::max(max_cond, kappa);
      // The closed form must also equal |det| of the analytic 2x2 matrix (an identity).
      const double err_det = std::abs(std::abs(ch.jac().determinant()) / (ch.s * ch.s) - an) / an;
      const double e = std::max(err, err_det);
      worst = std::max(worst, std::isfinite(e) ? e : kInfinity);
      if (!(e < 1e-6)) {
        ++fails;
        if (first.empty()) first = fmt::format("{} config {} (rel. error {:.3g})", hc.name, k, e);
      }
      if (negative_control) {
        // The Taylor test alone (differentiation tolerances lifted) on a 2x2 matrix off by 1e-4 of
        // its largest entry in one entry: its remainder has a linear term, the slope falls to ~1.
        stats::FdOptions taylor_only = fo;
        taylor_only.tolerance = taylor_only.ridders_tolerance = kInfinity;
        const auto pr = stats::check_jacobian_at(
            [&](const Eigen::VectorXd& x) { return ch.f(x); },
            [&](const Eigen::VectorXd&) {
              Eigen::MatrixXd j = ch.jac();
              j(0, 0) += 1e-4 * j.cwiseAbs().maxCoeff();
              return j;
            },
            Eigen::VectorXd::Zero(2), taylor_only, static_cast<uint64_t>(k));
        if (!pr.passed) ++fd_matrix_fail;
      } else {
        // The full analytic 2x2 matrix against central differences, Ridders and a Taylor test.
        const auto pr = stats::check_jacobian_at([&](const Eigen::VectorXd& x) { return ch.f(x); },
                                                 [&](const Eigen::VectorXd&) { return ch.jac(); }, Eigen::VectorXd::Zero(2),
                                                 fo, static_cast<uint64_t>(k));
        if (!(pr.ridders_rel_error < fo.ridders_tolerance)) ++ridders_disagree;
        if (pr.skipped) ++skipped;
        if (pr.taylor_directions_used > 1) ++redrawn;
        if (!std::isnan(pr.taylor_slope)) worst_slope_dev = std::max(worst_slope_dev, std::fabs(pr.taylor_slope - 2));
        // Central differences (1e-6), Ridders (1e-6) and the Taylor slope (2 +- 0.1) must all agree.
        if (pr.nonfinite || !pr.passed) {
          ++fd_matrix_fail;
          if (first.empty())
            first = fmt::format("{} config {}: 2x2 matrix CD err {:.2e}, Ridders err {:.2e}, Taylor slope {:.3f}", hc.name,
                                k, pr.rel_error, pr.ridders_rel_error, pr.taylor_slope);
        }
        worst_matrix = std::max(worst_matrix, pr.rel_error);
        max_cond = std::max(max_cond, pr.condition_number);
      }
    }
    per[hc.name] = {{"configurations", n}, {"failed", fails}, {"worst_rel_error", worst},
                    {"worst_matrix_rel_error", worst_matrix}, {"max_condition_number", max_cond}};
    res.statistic = std::max(res.statistic, worst);
    total_fail += fails;
    total += n;
  }
  res.samples = total;
  res.details["cases"] = per;
  res.details["matrix_failures"] = fd_matrix_fail;
  res.details["matrix_skipped"] = skipped;
  res.details["ridders_disagreements"] = ridders_disagree;
  res.details["taylor_directions_redrawn"] = redrawn;
  res.details["worst_taylor_slope_deviation"] = worst_slope_dev;
  const bool all_ok = total_fail == 0 && fd_matrix_fail == 0;
  // The control must be caught by both parts: the closed form of |dh/do| and the Taylor test of
  // the perturbed matrix (each in more than half of the configurations).
  res.passed = negative_control ? total_fail > total / 2 && fd_matrix_fail > total / 2 : all_ok;
  res.message = fmt::format("{} configurations in {} named cases: {} fail |dh/do| (tol 1e-6), worst {:.2e}; "
                            "(error / condition number); 2x2 matrix vs FD/Ridders (1e-6)/Taylor slope (2 +- 0.1): {} fail "
                            "({} Ridders, worst |slope - 2| {:.3f}, {} needed a second direction), {} skipped{}",
                            total, std::size(kHvCases), total_fail, res.statistic, fd_matrix_fail, ridders_disagree,
                            worst_slope_dev, redrawn, skipped,
                            first.empty() ? "" : "; first: " + first);
  if (negative_control)
    res.message = (res.passed ? "wrong Jacobian rejected: " : "wrong Jacobian NOT rejected: ") + res.message;
  return res;
}

TB_REGISTER_CHECK({.name = "material.half_vector.jacobian_fd",
                   .description = "|d omega_h / d omega_o| (Kaplanyan 2014 Eq. 10) against central finite "
                                  "differences, rel. error < 1e-6, named hard cases",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& ctx) {
                     return run_half_vector_fd(
                         ctx, [](const HvConfig& c) { return half_vector_jacobian(c.i, c.o, c.eta_i, c.eta_o); }, false);
                   }});

TB_REGISTER_CHECK({.name = "material.half_vector.jacobian_fd.negative_control",
                   .description = "The finite-difference check rejects |dh/do| with the eta_o^2 factor dropped, and its Taylor test alone a 2x2 Jacobian off by 1e-4 in one entry",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& ctx) {
                     return run_half_vector_fd(
                         ctx,
                         [](const HvConfig& c) {
                           return half_vector_jacobian(c.i, c.o, c.eta_i, c.eta_o) / (c.eta_o * c.eta_o);
                         },
                         true);
                   }});

}  // namespace
}  // namespace tb

// Registered checks of the sampling warps of lib/core (docs/validation.md A): a chi-square fit of
// each warp's samples against its own pdf (alpha = 0.01, Sidak over the configurations of a
// warp), deterministic inverse round trips, and a negative control the chi-square test must
// reject.
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/discrete.h"
#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "lib/core/truncated_normal.h"
#include "lib/core/warp_disk.h"
#include "lib/core/warp_sphere.h"
#include "lib/core/warp_triangle.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/registry.h"

namespace tb {
namespace {

constexpr double kAlpha = 0.01;        // per warp, before Sidak over its configurations
constexpr double kInverseTol = 1e-9;   // round trips in the uniforms

double sidak(double alpha, size_t m) { return 1.0 - std::pow(1.0 - alpha, 1.0 / static_cast<double>(m)); }

// One configuration of a warp: label and a function running the chi-square test.
struct Chi2Config {
  std::string label;
  std::function<SamplerChi2Result(const SamplerChi2Options&)> run;
};

CheckResult run_configs(const CheckContext& ctx, const std::string& name, int64_t quick, int64_t full,
                        const std::vector<Chi2Config>& configs, bool attach_heatmaps = false) {
  CheckResult res;
  res.statistic_name = "min p";
  res.alpha = sidak(kAlpha, configs.size());
  res.passed = true;
  double min_p = 1;
  std::string worst_label;
  nlohmann::json per = nlohmann::json::array();
  for (size_t k = 0; k < configs.size(); ++k) {
    SamplerChi2Options o;
    o.samples = ctx.size(quick, full);
    o.seed = ctx.seed;
    o.key = hash_string(name + "/" + configs[k].label);
    const SamplerChi2Result r = configs[k].run(o);
    const bool ok = r.passed(res.alpha);
    res.passed = res.passed && ok;
    state_chi2_power(res, r, res.alpha);
    res.samples += r.samples;
    if (r.p_value() <= min_p) {
      min_p = r.p_value();
      worst_label = configs[k].label + ": " + r.message();
    }
    nlohmann::json d = r.details();
    d["configuration"] = configs[k].label;
    d["passed"] = ok;
    per.push_back(d);
    if (attach_heatmaps && k == 0) {
      res.plots.push_back(r.observed_heatmap(name + " " + configs[k].label + ": observed counts"));
      res.plots.push_back(r.expected_heatmap(name + " " + configs[k].label + ": expected counts"));
    }
    ctx.progress(static_cast<double>(k + 1) / static_cast<double>(configs.size()));
  }
  res.statistic = min_p;
  res.p_value = min_p;
  res.details["configurations"] = per;
  res.details["alpha_per_warp"] = kAlpha;
  res.details["alpha_sidak"] = res.alpha;
  res.message = fmt::format("{} of {} configuration(s) at alpha' = {:.3g}; smallest p: {}",
                            res.passed ? "all pass" : "REJECTED", configs.size(), res.alpha, worst_label);
  return res;
}

// --- The warps under test ------------------------------------------------------------------

const Vec2 kTri[3] = {{0.1, 0.2}, {0.9, 0.1}, {0.4, 0.95}};

double triangle_pdf(const Vec2& p) {
  // Inside test by the signs of the three edge functions (the triangle is counter-clockwise).
  auto edge = [](const Vec2& a, const Vec2& b, const Vec2& q) {
    return difference_of_products(b.x - a.x, q.y - a.y, b.y - a.y, q.x - a.x);
  };
  const bool inside = edge(kTri[0], kTri[1], p) >= 0 && edge(kTri[1], kTri[2], p) >= 0 && edge(kTri[2], kTri[0], p) >= 0;
  return inside ? pdf_uniform_triangle(kTri[0], kTri[1], kTri[2]) : 0.0;
}

struct TnSetting {
  double mu, sigma, a, b;
  std::string label() const { return fmt::format("mu={} sigma={} [{}, {}]", mu, sigma, a, b); }
};
// The lens perturbation's range (Otsu et al.: [-pi, pi]), tails on both sides, the
// long-double regime (40 sigma), huge sigma (nearly uniform), a narrow interval.
const std::vector<TnSetting> kTnSettings = {
    {0, 0.5, -kPi, kPi}, {0, 1, 3, 4}, {0, 1, -4, -3}, {0, 1, 40, 41}, {0, 1e6, 1, 2}, {1, 2, 2, 2.000001},
};

const std::vector<double> kDiscreteWeights = {0, 3, 0.5, 0, 1, 7, 0.01, 2, 0, 4.5, 0.25};

// An interval chi-square test of a discrete distribution: index i is the point i + 0.5 and
// the pdf is the pmf on [i, i + 1).
template <class D>
Chi2Config discrete_config(const std::string& label, const D& dist) {
  return {label, [dist](const SamplerChi2Options& o) {
            const int n = static_cast<int>(dist.size());
            return chi2_test(
                Chi2Domain::interval(0, n, n),
                [&](Vec2 u) { return static_cast<double>(dist.sample(u.x).index) + 0.5; },
                [&](double x) { return dist.pmf(std::min(static_cast<size_t>(x), dist.size() - 1)); }, o);
          }};
}

// --- chi-square checks ----------------------------------------------------------------------

// Rectangles cut by a curve or an edge of the support: nested adaptive quadrature would bisect
// to full depth along the edge; 3 levels at tolerance 1e-6 give expected counts to ~1e-4
// relative, far below the Poisson noise 1/sqrt(E) ~ 5% of a cell.
SamplerChi2Options edge_cut(SamplerChi2Options o) {
  o.quadrature_max_depth = 3;
  o.quadrature_tolerance = 1e-6;
  return o;
}

CheckResult chi2_disk(const CheckContext& ctx) {
  return run_configs(ctx, "core.warp.disk_concentric.chi2", 500000, 4000000,
                     {{"unit disk on [-1,1]^2, 51 x 51", [](const SamplerChi2Options& o) {
                         return chi2_test(Chi2Domain::rectangle({-1, -1}, {1, 1}, 51, 51), sample_uniform_disk_concentric,
                                          pdf_uniform_disk, edge_cut(o));
                       }}});
}
CheckResult chi2_sphere(const CheckContext& ctx) {
  return run_configs(ctx, "core.warp.uniform_sphere.chi2", 1000000, 4000000,
                     {{"sphere 101 x 51", [](const SamplerChi2Options& o) {
                         return chi2_test(Chi2Domain::sphere(), sample_uniform_sphere,
                                          [](const Vec3&) { return pdf_uniform_sphere(); }, o);
                       }}});
}
CheckResult chi2_hemisphere(const CheckContext& ctx) {
  return run_configs(ctx, "core.warp.uniform_hemisphere.chi2", 1000000, 4000000,
                     {{"hemisphere 101 x 51", [](const SamplerChi2Options& o) {
                         return chi2_test(Chi2Domain::hemisphere(), sample_uniform_hemisphere, pdf_uniform_hemisphere, o);
                       }}});
}
CheckResult chi2_cosine(const CheckContext& ctx) {
  return run_configs(ctx, "core.warp.cosine_hemisphere.chi2", 1000000, 4000000,
                     {{"hemisphere 101 x 51", [](const SamplerChi2Options& o) {
                         return chi2_test(Chi2Domain::hemisphere(), sample_cosine_hemisphere, pdf_cosine_hemisphere, o);
                       }}},
                     /*attach_heatmaps=*/true);
}
CheckResult chi2_cone(const CheckContext& ctx) {
  std::vector<Chi2Config> configs;
  for (double c : {0.95, 0.3, -0.6}) {
    configs.push_back({fmt::format("cos_theta_max={}, cap cos >= {}", c, c), [c](const SamplerChi2Options& o) {
                         // The cap domain starts a little below the cone so its rim lies inside a row.
                         const double lo = std::max(-1.0, c - 0.013 * (1 - c));
                         return chi2_test(
                             Chi2Domain::spherical_cap(lo), [c](Vec2 u) { return sample_uniform_cone(u, c); },
                             [c](const Vec3& w) { return pdf_uniform_cone(w, c); }, o);
                       }});
  }
  return run_configs(ctx, "core.warp.uniform_cone.chi2", 300000, 2000000, configs);
}
CheckResult chi2_triangle(const CheckContext& ctx) {
  return run_configs(ctx, "core.warp.uniform_triangle.chi2", 500000, 4000000,
                     {{"triangle (0.1,0.2) (0.9,0.1) (0.4,0.95) on [0,1]^2, 51 x 51", [](const SamplerChi2Options& o) {
                         return chi2_test(
                             Chi2Domain::rectangle({0, 0}, {1, 1}, 51, 51),
                             [](Vec2 u) { return sample_uniform_triangle(kTri[0], kTri[1], kTri[2], u); }, triangle_pdf,
                             edge_cut(o));
                       }}});
}
CheckResult chi2_truncated_normal(const CheckContext& ctx) {
  std::vector<Chi2Config> configs;
  for (const TnSetting& s : kTnSettings) {
    configs.push_back({s.label(), [s](const SamplerChi2Options& o) {
                         const TruncatedNormal t = *TruncatedNormal::create(s.mu, s.sigma, s.a, s.b);
                         return chi2_test(
                             Chi2Domain::interval(s.a, s.b, 101), [&](Vec2 u) { return t.sample(u.x); },
                             [&](double x) { return t.pdf(x); }, o);
                       }});
  }
  return run_configs(ctx, "core.warp.truncated_normal.chi2", 100000, 1000000, configs);
}
CheckResult chi2_discrete(const CheckContext& ctx) {
  std::vector<double> many(257);
  for (size_t i = 0; i < many.size(); ++i) many[i] = (i % 5 == 0) ? 0.0 : static_cast<double>(mix_bits(i) % 1000) + 1;
  return run_configs(ctx, "core.warp.discrete.chi2", 500000, 4000000,
                     {discrete_config("alias, 11 weights with zeros", *AliasTable::create(kDiscreteWeights)),
                      discrete_config("cdf, 11 weights with zeros", *DiscreteCdf::create(kDiscreteWeights)),
                      discrete_config("alias, 257 weights, every 5th zero", *AliasTable::create(many)),
                      discrete_config("cdf, 257 weights, every 5th zero", *DiscreteCdf::create(many))});
}

// The negative control: the cosine-hemisphere sampler tested against a pdf that is 2% too
// high where cos(theta) > 0.5 (mass 3/4 under the true density) and renormalised below
// (factor (1 - 0.765)/0.25 = 0.94). Noncentrality at N = 1e6: N sum (p - q)^2 / q ~ 1250
// against dof ~ 5000 (sd ~ 100): the test has power ~1 at alpha = 0.01.
double perturbed_cosine_pdf(const Vec3& w) {
  const double p = pdf_cosine_hemisphere(w);
  return w.z > 0.5 ? 1.02 * p : (1.0 - 1.02 * 0.75) / 0.25 * p;
}
CheckResult negative_control(const CheckContext& ctx) {
  SamplerChi2Options o;
  o.samples = ctx.size(1000000, 4000000);
  o.seed = ctx.seed;
  o.key = hash_string("core.warp.negative_control");
  const SamplerChi2Result r = chi2_test(Chi2Domain::hemisphere(), sample_cosine_hemisphere, perturbed_cosine_pdf, o);
  CheckResult res;
  res.alpha = kAlpha;
  res.passed = !r.passed(kAlpha);
  res.statistic_name = "p (must be < alpha)";
  res.statistic = r.p_value();
  res.p_value = r.p_value();
  res.samples = r.samples;
  res.details = r.details();
  res.message = fmt::format("cosine hemisphere against a pdf 2% off on cos > 0.5: {} ({})",
                            res.passed ? "rejected as it must be" : "NOT rejected", r.message());
  return res;
}

// --- Inverse round trips (deterministic) ---------------------------------------------------

double wrap(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 1.0 - d);
}

// Max round-trip error over n seeded uniforms, skipping points where the warp is singular
// (poles, the disk centre, triangle vertex): such points are counted.
template <class Roundtrip>
CheckResult inverse_check(const CheckContext& ctx, const std::string& name, Roundtrip&& roundtrip,
                          int64_t quick = 200000) {
  const int64_t n = ctx.size(quick, 10 * quick);
  double worst = 0;
  int64_t skipped = 0, worst_index = -1;
  for (int64_t i = 0; i < n; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, hash_string(name), static_cast<uint64_t>(i));
    const Vec2 u = rng.uniform2();
    const double e = roundtrip(u);
    if (e < 0) {
      ++skipped;
      continue;
    }
    if (!(e <= worst)) {
      worst = e;
      worst_index = i;
    }
  }
  CheckResult res;
  res.passed = worst <= kInverseTol;
  res.statistic_name = "max round-trip error";
  res.statistic = worst;
  res.samples = n;
  res.details = {{"tolerance", kInverseTol}, {"skipped_singular", skipped}, {"worst_index", worst_index}};
  res.message = fmt::format("max |inverse(sample(u)) - u| = {:.3g} (tolerance {:.0e}) over {} points, {} singular "
                            "points skipped",
                            worst, kInverseTol, n - skipped, skipped);
  return res;
}

CheckResult inverse_disk(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.disk_concentric.inverse", [](Vec2 u) {
    const Vec2 v = invert_uniform_disk_concentric(sample_uniform_disk_concentric(u));
    return std::max(std::abs(v.x - u.x), std::abs(v.y - u.y));
  });
}
template <class S, class I>
double direction_roundtrip(Vec2 u, S sample, I invert) {
  const Vec3 w = sample(u);
  if (sin_theta(w) < 1e-6) return -1;  // phi undefined at the poles
  const Vec2 v = invert(w);
  return std::max(std::abs(v.x - u.x), wrap(v.y, u.y));
}
CheckResult inverse_sphere(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.uniform_sphere.inverse",
                       [](Vec2 u) { return direction_roundtrip(u, sample_uniform_sphere, invert_uniform_sphere); });
}
CheckResult inverse_hemisphere(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.uniform_hemisphere.inverse",
                       [](Vec2 u) { return direction_roundtrip(u, sample_uniform_hemisphere, invert_uniform_hemisphere); });
}
CheckResult inverse_cosine(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.cosine_hemisphere.inverse", [](Vec2 u) {
    const Vec3 w = sample_cosine_hemisphere(u);
    // At the horizon z = sqrt(1 - r^2) is flat in r: skip (counted) the band z < 1e-4.
    if (w.z < 1e-4) return -1.0;
    const Vec2 v = invert_cosine_hemisphere(w);
    return std::max(std::abs(v.x - u.x), std::abs(v.y - u.y));
  });
}
CheckResult inverse_cone(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.uniform_cone.inverse", [](Vec2 u) {
    double worst = 0;
    for (double c : {0.95, 0.3, -0.6}) {
      const double e = direction_roundtrip(
          u, [c](Vec2 v) { return sample_uniform_cone(v, c); }, [c](const Vec3& w) { return invert_uniform_cone(w, c); });
      if (e < 0) return -1.0;
      worst = std::max(worst, e);
    }
    return worst;
  });
}
CheckResult inverse_triangle(const CheckContext& ctx) {
  return inverse_check(ctx, "core.warp.uniform_triangle.inverse", [](Vec2 u) {
    if (u.x < 1e-12) return -1.0;  // the vertex b0 = 1, where u1 is lost
    const Vec2 v = invert_uniform_triangle_barycentrics(sample_uniform_triangle_barycentrics(u));
    return std::max(std::abs(v.x - u.x), std::abs(v.y - u.y));
  });
}
CheckResult inverse_truncated_normal(const CheckContext& ctx) {
  std::vector<TruncatedNormal> tn;
  for (const TnSetting& s : kTnSettings) tn.push_back(*TruncatedNormal::create(s.mu, s.sigma, s.a, s.b));
  return inverse_check(ctx, "core.warp.truncated_normal.inverse", [&](Vec2 u) {
    double worst = 0;
    for (const TruncatedNormal& t : tn) {
      const double x = t.sample(u.x);
      // Error relative to the tolerance plus what a few ulps of x cost in u (intrinsic for
      // an interval only a few million doubles wide), scaled back to the 1e-9 budget.
      const double allowed = kInverseTol + 8 * t.pdf(x) * kEpsilon * (std::abs(x) + std::abs(t.mu()));
      worst = std::max(worst, std::abs(t.cdf(x) - u.x) / allowed * kInverseTol);
    }
    return worst;
  }, /*quick=*/20000);
}
CheckResult inverse_discrete(const CheckContext& ctx) {
  const DiscreteCdf d = *DiscreteCdf::create(kDiscreteWeights);
  return inverse_check(ctx, "core.warp.discrete.inverse", [&](Vec2 u) {
    const DiscreteSample s = d.sample(u.x);
    return std::abs(d.invert(s.index, s.u_remapped) - u.x);
  });
}

// --- Registration ---------------------------------------------------------------------------

#define TB_WARP_CHI2(NAME, FN, WHAT)                                                                          \
  TB_REGISTER_CHECK({.name = "core.warp." NAME ".chi2",                                                      \
                     .description = "Chi-square fit of " WHAT " samples against its pdf (alpha 0.01, Sidak)", \
                     .kind = CheckKind::kStatistical,                                                        \
                     .run = FN})
#define TB_WARP_INVERSE(NAME, FN, WHAT)                                                                 \
  TB_REGISTER_CHECK({.name = "core.warp." NAME ".inverse",                                             \
                     .description = "Inverse of " WHAT " round-trips the uniforms to 1e-9",             \
                     .kind = CheckKind::kDeterministic,                                                \
                     .run = FN})

TB_WARP_CHI2("disk_concentric", chi2_disk, "the concentric disk");
TB_WARP_CHI2("uniform_sphere", chi2_sphere, "the uniform sphere");
TB_WARP_CHI2("uniform_hemisphere", chi2_hemisphere, "the uniform hemisphere");
TB_WARP_CHI2("cosine_hemisphere", chi2_cosine, "the cosine-weighted hemisphere");
TB_WARP_CHI2("uniform_cone", chi2_cone, "the uniform cone (3 apertures)");
TB_WARP_CHI2("uniform_triangle", chi2_triangle, "the uniform triangle");
TB_WARP_CHI2("truncated_normal", chi2_truncated_normal, "the truncated normal (6 settings)");
TB_WARP_CHI2("discrete", chi2_discrete, "the alias table and the CDF table (4 settings)");
TB_WARP_INVERSE("disk_concentric", inverse_disk, "the concentric disk");
TB_WARP_INVERSE("uniform_sphere", inverse_sphere, "the uniform sphere");
TB_WARP_INVERSE("uniform_hemisphere", inverse_hemisphere, "the uniform hemisphere");
TB_WARP_INVERSE("cosine_hemisphere", inverse_cosine, "the cosine-weighted hemisphere");
TB_WARP_INVERSE("uniform_cone", inverse_cone, "the uniform cone");
TB_WARP_INVERSE("uniform_triangle", inverse_triangle, "the uniform triangle");
TB_WARP_INVERSE("truncated_normal", inverse_truncated_normal, "the truncated normal (its CDF)");
TB_WARP_INVERSE("discrete", inverse_discrete, "the discrete CDF table");

TB_REGISTER_CHECK({.name = "core.warp.negative_control",
                   .description = "The chi-square tester rejects the cosine hemisphere against a pdf 2% off on "
                                  "cos(theta) > 0.5 (passes iff rejected)",
                   .kind = CheckKind::kStatistical,
                   .run = negative_control});

}  // namespace
}  // namespace tb

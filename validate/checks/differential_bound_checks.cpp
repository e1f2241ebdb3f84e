// Registered checks of the variance bound of Zirr & Dachsbacher 2020 against measured variance,
// the experiment of Fig. 3 / Sec. 8.5 (validate/differential/bound_experiment.h has the bound and
// why the test is a binomial one; docs/zirr2020.md):
//   differential.bound.eq21.diffuse      r~ of Eq. 21, paths of 2 vertices (one diffuse bounce)
//   differential.bound.eq21.two_bounce   r~ of Eq. 21, paths of 3 vertices (floor, wall, emitter)
//   differential.bound.eq20.diffuse      r~ of Eq. 20 (full differentials, PCA plane), 2 vertices
// each: per pixel of a 4x4 grid and per 2x2 sub-pixel subfilter of each, the measured relative
// variance V/I^2 of the path tracer's samples must not exceed the bound r~ of Prop. 3 / Eq. 14-16
// (one-sided exact binomial test, Šidák over the 80 units at alpha = 1e-5); the slack
// bound / measured is reported (min, median, max), with the reweighted splats S N / (kappa r~).
// Negative control:
//   differential.bound.negative_control  Eq. 21 without p(i_1) (validate/differential/bound_broken.h)
//                                        must be rejected by the same test.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "validate/differential/bound_broken.h"
#include "validate/differential/bound_experiment.h"
#include "validate/registry.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

constexpr double kAlpha = 1e-5;  // docs/validation.md, "Budget, seeds and determinism"
// Hit values must be one constant (Lambertian scene, constant emission) for the binomial form.
constexpr double kConstantValueTolerance = 1e-9;

struct BoundRun {
  std::vector<bound::PixelStats> pixels;
  double p_min = 1.0, alpha = kAlpha;
  int64_t units = 0, rejected = 0, untested_pixels = 0, samples = 0;
  bool constant_values = true;
  bound::BoundRule rule = bound::BoundRule::kMin;
  bound::SlackSummary pixel_slack_r_min;
  bound::SlackSummary pixel_slack, sub_slack;
  double max_reweighted = 0.0;  // max over pixels of E[(S/r~)^2] r~_min / I^2 (<= 1 by the bound)
};

struct BoundSetup {
  std::string name;
  int k = 2;
  bound::RatioFn ratio;
  bound::BoundRule rule = bound::BoundRule::kMin;
  int64_t quick = 131072, full = 1048576;  // samples per pixel
};

BoundRun run_bound(const CheckContext& ctx, const BoundSetup& su) {
  const std::string& name = su.name;
  const int k = su.k;
  const bound::RatioFn& ratio = su.ratio;
  static const std::unique_ptr<World> world = bound::make_world(bound::BoundScene{});
  bound::RunConfig cfg;
  cfg.k = k;
  cfg.samples_per_pixel = ctx.size(su.quick, su.full);
  cfg.seed = ctx.seed;
  cfg.key = hash_string(name);
  BoundRun r;
  r.rule = su.rule;
  r.pixels = bound::run(*world, cfg, ratio);
  std::vector<const bound::UnitStats*> px, sub;
  for (const bound::PixelStats& p : r.pixels) {
    px.push_back(&p.pixel_unit);
    for (const bound::UnitStats& s : p.sub) sub.push_back(&s);
    if (p.pixel_unit.hits == 0) ++r.untested_pixels;
    r.samples += p.pixel_unit.n;
    const bound::UnitStats& u = p.pixel_unit;
    if (u.hits > 0) {
      if (u.s_max > u.s_min * (1.0 + kConstantValueTolerance)) r.constant_values = false;
      const double mean = u.sum / static_cast<double>(u.n);
      r.max_reweighted =
          std::max(r.max_reweighted, u.sum_w2 / static_cast<double>(u.n) * bound::bound(u, su.rule) / (mean * mean));
    }
  }
  std::vector<const bound::UnitStats*> all = px;
  all.insert(all.end(), sub.begin(), sub.end());
  r.units = static_cast<int64_t>(all.size());
  r.alpha = stats::sidak_alpha(kAlpha, r.units);
  for (const bound::UnitStats* u : all) {
    const double p = bound::conservative_p_value(*u, su.rule);
    r.p_min = std::min(r.p_min, p);
    if (p < r.alpha) ++r.rejected;
  }
  r.pixel_slack = bound::slack(px, su.rule);
  r.sub_slack = bound::slack(sub, su.rule);
  r.pixel_slack_r_min = bound::slack(px, bound::BoundRule::kMin);
  return r;
}

nlohmann::json run_details(const BoundRun& r) {
  nlohmann::json pixels = nlohmann::json::array();
  for (const bound::PixelStats& p : r.pixels) {
    nlohmann::json subs = nlohmann::json::array();
    for (const bound::UnitStats& s : p.sub) subs.push_back(bound::unit_json(s, r.rule));
    pixels.push_back({{"pixel", {p.pixel.x, p.pixel.y}}, {"unit", bound::unit_json(p.pixel_unit, r.rule)}, {"subfilters", subs}});
  }
  auto sl = [](const bound::SlackSummary& s) {
    return nlohmann::json{{"units", s.units}, {"min", s.min}, {"median", s.median}, {"max", s.max}};
  };
  return {{"scene", bound::scene_json(bound::BoundScene{})},
          {"bound_rule", r.rule == bound::BoundRule::kMin ? "min r~ over contributing paths" : "mean r~ over contributing paths"},
          {"slack_pixels_r_min", sl(r.pixel_slack_r_min)},
          {"alpha_family", kAlpha},
          {"alpha_per_unit", r.alpha},
          {"units", r.units},
          {"rejected", r.rejected},
          {"p_min", r.p_min},
          {"untested_pixels", r.untested_pixels},
          {"constant_hit_values", r.constant_values},
          {"slack_pixels", sl(r.pixel_slack)},
          {"slack_subfilters", sl(r.sub_slack)},
          {"max_reweighted_second_moment_times_r_over_I2", r.max_reweighted},
          {"pixels", pixels}};
}

std::string run_line(const BoundRun& r) {
  return fmt::format(
      "{} units (16 pixels + 64 subfilters), bound {} r~, {} rejected at alpha' = {:.3g} (min p {:.3g}); slack "
      "bound/measured: pixels min {:.3g} median {:.3g} max {:.3g}, subfilters min {:.3g} median {:.3g}{}; max "
      "E[(S/r~)^2] r~/I^2 = {:.3g}",
      r.units, r.rule == bound::BoundRule::kMin ? "min" : "mean", r.rejected, r.alpha, r.p_min, r.pixel_slack.min,
      r.pixel_slack.median, r.pixel_slack.max, r.sub_slack.min, r.sub_slack.median,
      r.rule == bound::BoundRule::kMin
          ? std::string()
          : fmt::format(" (with min r~: pixels min {:.3g} median {:.3g})", r.pixel_slack_r_min.min,
                        r.pixel_slack_r_min.median),
      r.max_reweighted);
}

CheckResult bound_check(const CheckContext& ctx, const BoundSetup& su) {
  const BoundRun r = run_bound(ctx, su);
  CheckResult out;
  out.passed = r.rejected == 0 && r.untested_pixels == 0 && r.constant_values;
  out.statistic_name = "min slack bound/measured (pixels)";
  out.statistic = r.pixel_slack.min;
  out.p_value = r.p_min;
  out.alpha = r.alpha;
  out.samples = r.samples;
  out.message = run_line(r);
  if (r.untested_pixels) out.message += fmt::format("; {} pixels without a contributing path", r.untested_pixels);
  if (!r.constant_values) out.message += "; hit values not constant (the binomial form does not apply)";
  out.details = run_details(r);
  return out;
}

CheckResult bound_negative_control(const CheckContext& ctx) {
  const BoundRun r =
      run_bound(ctx, {.name = "differential.bound.negative_control", .k = 2, .ratio = bound::ratio_eq21_without_camera_density});
  CheckResult out;
  out.passed = r.rejected > 0;
  out.statistic_name = "units rejected";
  out.statistic = static_cast<double>(r.rejected);
  out.p_value = r.p_min;
  out.alpha = r.alpha;
  out.samples = r.samples;
  out.message = "Eq. 21 without p(i_1): " + run_line(r) + " -> " + (out.passed ? "caught" : "NOT caught");
  out.details = run_details(r);
  return out;
}

struct DifferentialBoundChecks {
  DifferentialBoundChecks() {
    auto& reg = Registry::global();
    reg.add({.name = "differential.bound.eq21.diffuse",
             .description = "Fig. 3: the path tracer's relative variance per pixel and per sub-pixel subfilter (one diffuse "
                            "bounce onto a square emitter) does not exceed r~ of Eq. 21 (Prop. 3, Eq. 14-16); one-sided "
                            "binomial test, Sidak over 80 units at alpha 1e-5",
             .kind = CheckKind::kStatistical,
             .run = [](const CheckContext& ctx) {
               return bound_check(ctx, {.name = "differential.bound.eq21.diffuse", .k = 2, .ratio = bound::ratio_eq21});
             }});
    reg.add({.name = "differential.bound.eq21.two_bounce",
             .description = "As differential.bound.eq21.diffuse for paths of 3 vertices (floor or wall, wall or floor, "
                            "emitter), the bound being the mean r~ of each unit's contributing paths",
             .kind = CheckKind::kStatistical,
             .run = [](const CheckContext& ctx) {
               // r~ spreads by 3-50x within a floor pixel here (the first bounce's pdf toward the
               // wall): the bound is the mean r~ over contributing paths, the min r~ reported.
               return bound_check(ctx, {.name = "differential.bound.eq21.two_bounce",
                                         .k = 3,
                                         .ratio = bound::ratio_eq21,
                                         .rule = bound::BoundRule::kMean,
                                         .quick = 1048576,
                                         .full = 4194304});
             }});
    reg.add({.name = "differential.bound.eq20.diffuse",
             .description = "As differential.bound.eq21.diffuse with r~ of Eq. 20 (full path differentials, PCA plane)",
             .kind = CheckKind::kStatistical,
             .run = [](const CheckContext& ctx) {
               return bound_check(ctx, {.name = "differential.bound.eq20.diffuse", .k = 2, .ratio = bound::ratio_eq20});
             }});
    reg.add({.name = "differential.bound.negative_control",
             .description = "r~ of Eq. 21 without the camera density p(i_1) is not conservative: the bound test must reject",
             .kind = CheckKind::kStatistical,
             .run = bound_negative_control});
  }
} const differential_bound_checks;

}  // namespace
}  // namespace tb

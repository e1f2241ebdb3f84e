// Registered checks of the cameras (lib/camera): raster <-> ray round trips, chi-square of lens
// and direction sampling against the stated densities (docs/validation.md A), the normalisation of
// We by quadrature (docs/camera.md), and negative controls for both.
#include <memory>
#include <vector>

#include <fmt/format.h>

#include "lib/camera/importance_integral.h"
#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"
#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "validate/chi2/direction_chart.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/registry.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

CameraSetup base_setup() {
  CameraSetup s;
  s.eye = {1.0, 2.0, -3.0};
  s.target = {0.2, 0.5, 1.0};
  s.up = {0.1, 1.0, 0.0};
  s.vfov_degrees = 70;
  s.width = 48;
  s.height = 36;
  s.lens_radius = 0.5;
  s.focus_distance = 3.0;
  return s;
}

std::vector<std::unique_ptr<Camera>> cameras() {
  std::vector<std::unique_ptr<Camera>> v;
  CameraSetup a = base_setup();
  v.push_back(std::make_unique<PinholeCamera>(a));
  a.vfov_degrees = 110;
  a.width = 17;
  a.height = 31;
  v.push_back(std::make_unique<PinholeCamera>(a));
  v.push_back(std::make_unique<ThinLensCamera>(base_setup()));
  a.lens_radius = 1.5;
  a.focus_distance = 0.7;
  v.push_back(std::make_unique<ThinLensCamera>(a));
  return v;
}

CheckResult run_roundtrip(const CheckContext& ctx) {
  const int64_t n = ctx.size(20000, 200000);
  double worst_raster = 0, worst_lens = 0;
  int64_t misses = 0;
  std::string worst_case;
  for (const auto& cam : cameras()) {
    for (int64_t i = 0; i < n; ++i) {
      Rng rng = Rng::for_sample(ctx.seed, hash_string("camera.roundtrip"), uint64_t(i));
      const Vec2 raster(rng.uniform() * cam->width(), rng.uniform() * cam->height());
      const Vec2 lens_u = rng.uniform2();
      const auto hit = cam->raster_from_ray(cam->generate_ray(raster, lens_u).ray);
      if (!hit) {
        ++misses;
        continue;
      }
      const double er = std::max(std::abs(hit->raster.x - raster.x), std::abs(hit->raster.y - raster.y));
      if (er > worst_raster) {
        worst_raster = er;
        worst_case = fmt::format("{} sample {} raster ({}, {}) lens_u ({}, {})", cam->name(), i, raster.x, raster.y,
                                 lens_u.x, lens_u.y);
      }
      if (!cam->lens_is_delta())
        worst_lens = std::max(worst_lens, std::max(std::abs(hit->lens_uniforms.x - lens_u.x),
                                                   std::abs(hit->lens_uniforms.y - lens_u.y)));
    }
  }
  CheckResult r;
  constexpr double kTol = 1e-9;  // the brief's round-trip tolerance (raster units / uniforms)
  r.passed = misses == 0 && worst_raster < kTol && worst_lens < kTol;
  r.statistic_name = "max abs error";
  r.statistic = std::max(worst_raster, worst_lens);
  r.samples = 4 * n;
  r.message = fmt::format("raster -> ray -> raster over 4 cameras: worst raster error {:.3g}, worst lens-uniform "
                          "error {:.3g}, {} rays not mapped back (tolerance {})",
                          worst_raster, worst_lens, misses, kTol);
  r.details = {{"worst_raster", worst_raster}, {"worst_lens_uniforms", worst_lens}, {"misses", misses},
               {"worst_case", worst_case}};
  return r;
}

// Lens points binned in (phi, s = r^2 / R^2): p(phi, s) = p_A R^2 / 2 (dA = R^2/2 ds dphi).
SamplerChi2Result lens_chi2(const CheckContext& ctx, bool broken) {
  const ThinLensCamera cam(base_setup());
  const double R = cam.lens_radius();
  SamplerChi2Options o;
  o.samples = ctx.size(200000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string(broken ? "camera.lens.chi2.negative" : "camera.lens.chi2");
  o.quadrature_tolerance = 1e-9;
  return chi2_test(
      Chi2Domain::rectangle({0, 0}, {2 * kPi, 1}, 31, 31),
      [&](Vec2 u) {
        const Vec3 p = cam.lens_point_camera(u);
        double phi = std::atan2(p.y, p.x);
        if (phi < 0) phi += 2 * kPi;
        return Vec2(phi, (p.x * p.x + p.y * p.y) / (R * R));
      },
      [&](Vec2 q) {
        const double r = R * std::sqrt(q.y);
        double pdf_area = cam.pdf_lens_area({r * std::cos(q.x), r * std::sin(q.x)});
        if (broken) pdf_area *= cam.lens_area();  // the 1 / (pi R^2) factor dropped
        return pdf_area * R * R / 2;
      },
      o);
}

constexpr double kChi2Alpha = 0.01;

CheckResult chi2_result(const SamplerChi2Result& s, double alpha, bool negative) {
  CheckResult r;
  const bool rejected = !s.passed(alpha);
  r.passed = negative ? rejected : !rejected;
  r.statistic_name = "chi2";
  r.statistic = s.gof.statistic;
  r.p_value = s.p_value();
  r.alpha = alpha;
  r.samples = s.samples;
  r.message = (negative ? std::string("negative control (must be rejected): ") : std::string()) + s.message();
  r.details = s.details();
  if (!negative) state_chi2_power(r, s, alpha);
  return r;
}

CheckResult run_lens_chi2(const CheckContext& ctx) {
  const SamplerChi2Result s = lens_chi2(ctx, false);
  CheckResult r = chi2_result(s, kChi2Alpha, false);
  r.plots.push_back(s.residual_heatmap("thin lens points: (O - E) / sqrt(E) in (phi, r^2/R^2)"));
  return r;
}
CheckResult run_lens_chi2_negative(const CheckContext& ctx) { return chi2_result(lens_chi2(ctx, true), kChi2Alpha, true); }

// Directions for a fixed lens point, binned in (a, b) = (atan(x/z), atan(y/z)) in camera space:
// dw = sec^2 a sec^2 b / (1 + tan^2 a + tan^2 b)^(3/2) da db; the image is a rectangle there.
SamplerChi2Result direction_chi2(const CheckContext& ctx, const Camera& cam, Vec2 lens_u, double h,
                                 const std::string& name) {
  SamplerChi2Options o;
  o.samples = ctx.size(200000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string("camera.directions.chi2." + name);
  o.quadrature_tolerance = 1e-9;
  const PerspectiveProjection& proj = cam.projection();
  const Vec3 lens_world = cam.generate_ray({0.5, 0.5}, lens_u).ray.o;
  const Vec3 lens = proj.to_camera_point(lens_world);
  const double tx = proj.tan_half_x(), ty = proj.tan_half_y();
  const Vec2 lo(std::atan((-h * tx - lens.x) / h), std::atan((-h * ty - lens.y) / h));
  const Vec2 hi(std::atan((h * tx - lens.x) / h), std::atan((h * ty - lens.y) / h));
  return chi2_test(
      Chi2Domain::rectangle(lo, hi, 41, 31),
      [&](Vec2 u) {
        const Vec3 d = proj.to_camera_dir(cam.generate_ray({u.x * cam.width(), u.y * cam.height()}, lens_u).ray.d);
        return Vec2(std::atan(d.x / d.z), std::atan(d.y / d.z));
      },
      [&](Vec2 ab) {
        const double ta = std::tan(ab.x), tb = std::tan(ab.y), n2 = 1 + ta * ta + tb * tb;
        const double jacobian = (1 + ta * ta) * (1 + tb * tb) / (n2 * std::sqrt(n2));
        return cam.pdf_we(Ray{lens_world, proj.to_world_dir(Vec3(ta, tb, 1.0) / std::sqrt(n2))}).dir * jacobian;
      },
      o);
}

CheckResult run_direction_chi2(const CheckContext& ctx) {
  const PinholeCamera pin(base_setup());
  const ThinLensCamera lens(base_setup());
  std::vector<std::pair<std::string, SamplerChi2Result>> cases;
  cases.emplace_back("pinhole", direction_chi2(ctx, pin, {0.5, 0.5}, 1.0, "pinhole"));
  cases.emplace_back("thin_lens_centre", direction_chi2(ctx, lens, {0.5, 0.5}, lens.focus_distance(), "centre"));
  cases.emplace_back("thin_lens_edge", direction_chi2(ctx, lens, {0.9, 0.2}, lens.focus_distance(), "edge"));
  const double alpha = stats::sidak_alpha(kChi2Alpha, int64_t(cases.size()));
  CheckResult r;
  r.passed = true;
  r.alpha = alpha;
  r.p_value = 1.0;
  r.statistic_name = "min p";
  std::string msg;
  for (const auto& [name, s] : cases) {
    r.passed = r.passed && s.passed(alpha);
    state_chi2_power(r, s, alpha);
    r.p_value = std::min(r.p_value, s.p_value());
    r.samples += s.samples;
    r.details[name] = s.details();
    msg += fmt::format("{}{}: p={:.3g}", msg.empty() ? "" : "; ", name, s.p_value());
  }
  r.statistic = r.p_value;
  r.message = fmt::format("ray directions vs pdf_dir (solid angle), {} configurations, Sidak alpha {:.3g}: {}",
                          cases.size(), alpha, msg);
  return r;
}

// int_image We cos dw * A_lens = 1 from several lens points (nested Gauss-Kronrod).
CheckResult run_importance(const CheckContext&, bool broken) {
  double worst = 0;
  nlohmann::json cases = nlohmann::json::array();
  for (const auto& cam : cameras()) {
    const auto* lens = dynamic_cast<const ThinLensCamera*>(cam.get());
    const double h = lens ? lens->focus_distance() : 1.0;
    const std::function<double(const Ray&)> we = [&](const Ray& r) {
      return broken ? cam->importance(r) * cam->lens_area() : cam->importance(r);
    };
    std::vector<Vec2> points = {{0, 0}};
    if (lens) points.insert(points.end(), {Vec2(0.3, -0.1) * lens->lens_radius(), Vec2(-0.3, 0.35) * lens->lens_radius()});
    for (const Vec2& p : points) {
      const double v = integrate_importance_cos(*cam, we, p, h) * cam->lens_area();
      worst = std::max(worst, std::abs(v - 1.0));
      cases.push_back({{"camera", cam->name()}, {"lens_point", {p.x, p.y}}, {"integral_times_lens_area", v}});
    }
  }
  // Quadrature at relative tolerance 1e-12 per level: 1e-9 leaves three orders of margin.
  constexpr double kTol = 1e-9;
  CheckResult r;
  const bool ok = worst < kTol;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "max |A_lens int We cos dw - 1|";
  r.statistic = worst;
  r.samples = int64_t(cases.size());
  r.message = fmt::format("{}normalisation of We over {} (camera, lens point) cases: worst deviation {:.3g} "
                          "(tolerance {})",
                          broken ? "negative control, We without 1/(pi r^2) (must fail): " : "", cases.size(), worst,
                          kTol);
  r.details = {{"cases", cases}};
  return r;
}

// ---- sample_wi (light tracing connections) ------------------------------------------------
// Thin lens: the lens point is uniform on the disk, so seen from a scene point `ref` the
// direction wi lies in the small cone subtended by the lens, with stated density
// d^2 / (cos_lens A_lens) w.r.t. solid angle at ref. It is tested on a zoomed cap around the
// direction to the lens centre (validate/chi2/direction_chart.h, d omega = dx dy / z). The stated
// pdf at an arbitrary direction w: the point where the line ref + t w crosses the lens plane
// (camera z = 0), its lens uniforms, and sample_wi's pdf there (0 off the lens).
SamplerChi2Result sample_wi_chi2(const CheckContext& ctx, const ThinLensCamera& cam, const Vec3& ref, bool broken,
                                 const std::string& name) {
  const PerspectiveProjection& proj = cam.projection();
  const Vec3 to_eye = proj.eye() - ref;
  const double d = glm::length(to_eye), R = cam.lens_radius();
  // The lens disk lies within angle asin(R / d) of the axis; the orthographic chart coordinate
  // of any of its points is at most sin of that angle = R / d. 5% margin.
  const Chi2DirectionChart chart = Chi2DirectionChart::around(to_eye / d, 1.05 * R / d, 31);
  const Vec3 ref_c = proj.to_camera_point(ref);
  SamplerChi2Options o;
  o.samples = ctx.size(200000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string((broken ? "camera.sample_wi.chi2.negative." : "camera.sample_wi.chi2.") + name);
  o.quadrature_tolerance = 1e-7;
  o.quadrature_max_depth = 4;  // rim cells: error ~1e-5 of a cell, far below 1/sqrt(E)
  return chi2_test_zoomed(
      chart,
      [&](Vec2 u) -> std::optional<Vec3> {
        const auto s = cam.sample_wi(ref, u);
        if (!s) return std::nullopt;
        return s->wi;
      },
      [&](const Vec3& w) {
        const Vec3 w_c = proj.to_camera_dir(w);
        if (!(w_c.z < 0.0)) return 0.0;
        const Vec3 p = ref_c + (-ref_c.z / w_c.z) * w_c;
        if (!(cam.pdf_lens_area({p.x, p.y}) > 0.0)) return 0.0;
        const auto s = cam.sample_wi(ref, cam.lens_uniforms({p.x, p.y, 0.0}));
        if (!s) return 0.0;
        const double cos_lens = glm::dot(proj.forward(), -s->wi);
        return broken ? s->pdf * cos_lens : s->pdf;  // broken: the cos factor dropped
      },
      o);
}

// Scene points seen by the base thin lens (eye + a right + b up + c forward): in focus
// off-axis, far and out of focus, and close (a wide cone); every lens point maps into the image.
std::vector<std::pair<std::string, Vec3>> sample_wi_refs(const PerspectiveProjection& proj) {
  const auto at = [&](double a, double b, double c) { return proj.to_world_point(Vec3(a, b, c)); };
  return {{"in_focus_off_axis", at(0.8, -0.5, 3.0)}, {"far_defocused", at(-1.0, 0.7, 9.0)},
          {"close", at(0.3, 0.2, 1.4)}};
}

// The pinhole's sample_wi is a Dirac connection: it must return the unit direction to the eye.
double pinhole_wi_error(const CheckContext& ctx, int64_t* bad) {
  const PinholeCamera pin(base_setup());
  double worst = 0;
  for (int64_t i = 0; i < 1000; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, hash_string("camera.sample_wi.pinhole"), uint64_t(i));
    const double z = 1.0 + 5.0 * rng.uniform();  // inside the view: |x|, |y| < 0.5 z
    const Vec3 c((rng.uniform() - 0.5) * z, (rng.uniform() - 0.5) * z, z);
    const Vec3 ref = pin.projection().to_world_point(c);
    const auto s = pin.sample_wi(ref, rng.uniform2());
    if (!s || !s->delta) {
      ++*bad;
      continue;
    }
    const Vec3 expect = glm::normalize(pin.projection().eye() - ref);
    worst = std::max(worst, glm::length(s->wi - expect));
  }
  return worst;
}

CheckResult run_sample_wi_chi2(const CheckContext& ctx, bool broken) {
  const ThinLensCamera cam(base_setup());
  std::vector<std::pair<std::string, SamplerChi2Result>> cases;
  for (const auto& [name, ref] : sample_wi_refs(cam.projection()))
    if (!broken || name == "in_focus_off_axis") cases.emplace_back(name, sample_wi_chi2(ctx, cam, ref, broken, name));
  const double alpha = stats::sidak_alpha(kChi2Alpha, int64_t(cases.size()));
  CheckResult r;
  r.alpha = alpha;
  r.p_value = 1.0;
  r.statistic_name = "min p";
  bool all_pass = true;
  std::string msg;
  for (const auto& [name, s] : cases) {
    all_pass = all_pass && s.passed(alpha);
    state_chi2_power(r, s, alpha);
    r.p_value = std::min(r.p_value, s.p_value());
    r.samples += s.samples;
    r.details[name] = s.details();
    msg += fmt::format("{}{}: p={:.3g} (off-chart/failed {})", msg.empty() ? "" : "; ", name, s.p_value(), s.failed);
  }
  r.statistic = r.p_value;
  if (broken) {
    r.passed = !all_pass;
    r.message = fmt::format("negative control, pdf without cos_lens (must be rejected): {}", msg);
    return r;
  }
  int64_t bad = 0;
  const double pin_err = pinhole_wi_error(ctx, &bad);
  constexpr double kPinTol = 1e-12;
  r.passed = all_pass && bad == 0 && pin_err < kPinTol;
  r.details["pinhole_max_direction_error"] = pin_err;
  r.details["pinhole_failed_or_not_delta"] = bad;
  r.message = fmt::format("thin-lens sample_wi directions vs stated pdf (solid angle at ref) on zoomed caps, {} "
                          "points, Sidak alpha {:.3g}: {}; pinhole wi error {:.2g} (tol {}), {} failed/non-delta",
                          cases.size(), alpha, msg, pin_err, kPinTol, bad);
  return r;
}

TB_REGISTER_CHECK({.name = "camera.roundtrip",
                   .description = "raster -> generate_ray -> raster_from_ray recovers raster position and lens "
                                  "uniforms to 1e-9 for pinhole and thin-lens cameras",
                   .kind = CheckKind::kDeterministic,
                   .run = run_roundtrip});
TB_REGISTER_CHECK({.name = "camera.lens.chi2",
                   .description = "thin-lens points (concentric disk) against pdf_pos = 1/(pi r^2), chi-square in "
                                  "(phi, r^2/R^2), alpha 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = run_lens_chi2});
TB_REGISTER_CHECK({.name = "camera.lens.chi2_negative_control",
                   .description = "the lens chi-square rejects a pdf missing the 1/(pi r^2) factor",
                   .kind = CheckKind::kStatistical,
                   .run = run_lens_chi2_negative});
TB_REGISTER_CHECK({.name = "camera.directions.chi2",
                   .description = "directions of generated rays (fixed lens point) against pdf_dir = 1/(A cos^3), "
                                  "chi-square in gnomonic angles, 3 configurations, Sidak alpha 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = run_direction_chi2});
TB_REGISTER_CHECK({.name = "camera.importance.normalisation",
                   .description = "quadrature of We cos over the image times the lens area equals 1",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_importance(c, false); }});
TB_REGISTER_CHECK({.name = "camera.importance.normalisation_negative_control",
                   .description = "the normalisation check rejects a thin-lens We missing 1/(pi r^2)",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_importance(c, true); }});

TB_REGISTER_CHECK({.name = "camera.sample_wi.chi2",
                   .description = "thin-lens sample_wi directions from 3 scene points against the stated pdf "
                                  "(solid angle) on a zoomed cap, Sidak alpha 0.01; pinhole wi is the eye direction",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_sample_wi_chi2(c, false); }});
TB_REGISTER_CHECK({.name = "camera.sample_wi.chi2_negative_control",
                   .description = "the sample_wi chi-square rejects a pdf missing the cos factor at the lens",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_sample_wi_chi2(c, true); }});

}  // namespace
}  // namespace tb

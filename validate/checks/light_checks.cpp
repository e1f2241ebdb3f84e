// Emitters: next-event sampling (sample_li) and emission sampling (sample_le) against their
// stated solid-angle densities (chi-square, docs/validation.md A), unbiasedness of next-event
// estimation of irradiance against a closed form, and a negative control.
#include <algorithm>
#include <memory>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/geometry/cylinder.h"
#include "lib/geometry/disk.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/paraboloid.h"
#include "lib/geometry/rectangle.h"
#include "lib/geometry/scene.h"
#include "lib/geometry/spawn.h"
#include "lib/geometry/sphere.h"
#include "lib/geometry/torus.h"
#include "lib/light/area_light.h"
#include "lib/light/infinite_lights.h"
#include "lib/light/point_light.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/registry.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb {
namespace {
using namespace stats;

constexpr double kAlpha = 0.01;  // per check, Šidák over the configurations inside it

// One emitter (shape id 0) in an otherwise empty scene, with the chart its samples are binned
// in: the shape's own (u, v) for analytic shapes, the quad's object-space (x, y) for the mesh.
// In both the emitter's outline is the domain boundary, so no grid cell is cut by a silhouette.
struct LightFixture {
  std::unique_ptr<Scene> scene = std::make_unique<Scene>();
  std::unique_ptr<AreaLight> light;
  std::string label;
  bool mesh = false;
  AffineTransform mesh_to_world;  // the mesh: object (quad) space to world
  Chi2Domain chart = Chi2Domain::rectangle(Vec2(0.0), Vec2(1.0), 41, 41);

  // Chart coordinates of a world point on the emitter; a point off the emitter maps outside
  // the chart (a hard failure of the test).
  Vec2 to_chart(const Vec3& p) const {
    if (mesh) {
      // Mesh vertices are stored in float: points within float rounding of the quad are on it.
      constexpr double kTol = 1e-6;
      const Vec3 q = mesh_to_world.inverse_point(p);
      const bool on = std::abs(q.z) <= kTol && std::abs(q.x) <= chart.x_max + kTol && std::abs(q.y) <= chart.y_max + kTol;
      return on ? Vec2(std::clamp(q.x, chart.x_min, chart.x_max), std::clamp(q.y, chart.y_min, chart.y_max)) : Vec2(-1e9);
    }
    const ShapeInstance& s = scene->analytic(0);
    return s.shape().project(s.to_world().inverse_point(p));
  }
  // The emitter point at chart coordinates c, and |dp/dc1 x dp/dc2| (world area per chart area).
  Hit at_chart(const Vec2& c, double* jacobian) const {
    if (mesh) {
      const Vec3 ex = mesh_to_world.vector(Vec3(1, 0, 0)), ey = mesh_to_world.vector(Vec3(0, 1, 0));
      Hit h;
      h.p = mesh_to_world.point(Vec3(c.x, c.y, 0.0));
      h.n = h.ng = glm::normalize(glm::cross(ex, ey));
      h.shape_id = 0;
      *jacobian = glm::length(glm::cross(ex, ey));
      return h;
    }
    const Hit h = scene->surface_at(0, 0, c);
    *jacobian = glm::length(glm::cross(h.dpdu, h.dpdv));
    return h;
  }
};

LightFixture make_fixture(const std::string& kind, bool two_sided) {
  LightFixture f;
  f.label = kind + (two_sided ? " (two-sided)" : "");
  uint32_t id = 0;
  auto add = [&](std::shared_ptr<const AnalyticShape> shape, const AffineTransform& xf) {
    return f.scene->add(ShapeInstance(std::move(shape), xf));
  };
  if (kind == "sphere") {
    id = add(std::make_shared<Sphere>(0.5), AffineTransform::translate(Vec3(0.3, -0.2, 2.0)));
  } else if (kind == "rectangle") {
    // Tilted, facing the origin side (normal +z rotated by 150 degrees about x: mostly -z).
    id = add(std::make_shared<Rectangle>(0.6, 0.3),
             AffineTransform::translate(Vec3(0.0, 0.4, 1.5)) * AffineTransform::rotate(150.0 * kPi / 180.0, Vec3(1, 0, 0)));
  } else if (kind == "disk") {
    id = add(std::make_shared<Disk>(0.7), AffineTransform::translate(Vec3(0.2, 0.1, -1.2)));
  } else if (kind == "cylinder") {
    id = add(std::make_shared<Cylinder>(0.4, -0.3, 0.3),
             AffineTransform::translate(Vec3(0.1, 0.2, 1.8)) * AffineTransform::rotate(1.1, Vec3(1, 0, 0)));
  } else if (kind == "paraboloid") {
    id = add(std::make_shared<Paraboloid>(0.5, 0.4),
             AffineTransform::translate(Vec3(-0.2, 0.1, 1.6)) * AffineTransform::rotate(2.2, Vec3(0, 1, 1)));
  } else if (kind == "torus") {
    id = add(std::make_shared<Torus>(0.5, 0.15),
             AffineTransform::translate(Vec3(0.1, -0.1, 2.0)) * AffineTransform::rotate(0.7, Vec3(1, 0, 0)));
  } else {  // "mesh": a quad as two triangles, tilted
    const TriangleMesh quad = make_quad_mesh(0.5, 0.4);
    f.mesh = true;
    f.mesh_to_world = AffineTransform::translate(Vec3(-0.3, 0.2, 1.0)) * AffineTransform::rotate(2.5, Vec3(1, 1, 0));
    f.chart = Chi2Domain::rectangle(Vec2(-0.5, -0.4), Vec2(0.5, 0.4), 41, 41);
    std::vector<Vec3> p;
    for (const Vec3& q : quad.positions()) p.push_back(f.mesh_to_world.point(q));
    id = f.scene->add(TriangleMesh(p, quad.triangles()));
  }
  f.scene->commit();
  f.light = std::make_unique<AreaLight>(*f.scene, id, Rgb(1.0), two_sided);
  return f;
}

// Next-event sampling is tested in the emitter's chart: each sample is binned at the chart
// coordinates of the point the sampler RETURNED (LightLiSample::hit.p, or LightLiPoint::p_light
// for sample_li_point, the path tracer's variant), so a sampler whose returned point is not the
// one its density describes is caught. The returned direction must point at that point, and
// sample_li's hit and p_light must agree; otherwise the sample is put outside the chart (a hard
// failure). The stated solid-angle density pdf_li is carried to chart measure with the
// Jacobian computed here, independently of the light code (Veach 1997, Eq. 8.10):
//   p(c) = pdf_li(ref, wi, hit) * |cos theta_light| / d^2 * |dp/dc1 x dp/dc2|.
// A pdf_li missing its 1/|cos theta_light| (the negative control) shows up as a wrong p(c).
SamplerChi2Result sample_li_chi2(const LightFixture& f, const Vec3& ref, int64_t n, uint64_t seed, uint64_t key,
                                 bool drop_cos, bool point_variant = false) {
  SamplerChi2Options opt{.samples = n, .seed = seed, .key = key};
  const Vec2 off_chart(-1e9);
  auto consistent = [&](const LightLiPoint& s, const Vec3& p) {
    const Vec3 d = p - ref;
    const double dist = glm::length(d);
    return glm::length(s.wi - d / dist) <= 1e-9 && std::abs(s.distance - dist) <= 1e-9 * dist;
  };
  return chi2_test(
      f.chart,
      [&](const Vec2& u) -> std::optional<Vec2> {
        if (point_variant) {
          const auto s = f.light->sample_li_point(ref, u);
          if (!s) return std::nullopt;
          return consistent(*s, s->p_light) ? f.to_chart(s->p_light) : off_chart;
        }
        const auto s = f.light->sample_li(ref, u);
        if (!s) return std::nullopt;
        const bool ok = consistent(*s, s->hit.p) && glm::length(s->p_light - s->hit.p) <= 1e-12 * glm::length(s->hit.p) &&
                        s->hit.shape_id == 0;
        return ok ? f.to_chart(s->hit.p) : off_chart;
      },
      [&](const Vec2& c) {
        double jacobian = 0.0;
        const Hit h = f.at_chart(c, &jacobian);
        const Vec3 d = h.p - ref;
        const double dist2 = glm::dot(d, d);
        const Vec3 wi = d / std::sqrt(dist2);
        const double cos_l = std::abs(glm::dot(h.n, wi));
        double pdf_w = f.light->pdf_li(ref, wi, &h);
        if (drop_cos) pdf_w *= cos_l;
        return pdf_w * cos_l / dist2 * jacobian;
      },
      opt);
}

CheckResult chi2_configs(const CheckContext& ctx, const std::string& name,
                         const std::vector<std::function<SamplerChi2Result(int64_t, uint64_t)>>& configs,
                         const std::vector<std::string>& labels, int64_t quick, int64_t full) {
  const int64_t n = ctx.size(quick, full);
  const double alpha = sidak_alpha(kAlpha, static_cast<int64_t>(configs.size()));
  CheckResult r;
  r.passed = true;
  r.alpha = alpha;
  r.statistic_name = "min p";
  r.statistic = 1.0;
  r.details["configurations"] = nlohmann::json::array();
  double min_p = 1.0;
  std::string worst;
  for (size_t i = 0; i < configs.size(); ++i) {
    const SamplerChi2Result res = configs[i](n, hash_values(ctx.seed, hash_string(name), i));
    const bool ok = res.passed(alpha);
    r.passed = r.passed && ok;
    state_chi2_power(r, res, alpha);
    r.samples += res.samples;
    nlohmann::json d = res.details();
    d["label"] = labels[i];
    d["passed"] = ok;
    r.details["configurations"].push_back(d);
    if (res.p_value() <= min_p) {
      min_p = res.p_value();
      worst = labels[i] + ": " + res.message();
      if (r.plots.empty() || !ok) r.plots = {res.residual_heatmap(labels[i] + ": (O - E)/sqrt(E)")};
    }
    ctx.progress(static_cast<double>(i + 1) / static_cast<double>(configs.size()));
  }
  r.statistic = min_p;
  r.p_value = std::min(1.0, sidak_adjust(min_p, static_cast<int64_t>(configs.size())));
  r.message = fmt::format("{} configurations, worst {}", configs.size(), worst);
  return r;
}

CheckResult run_sample_li_chi2(const CheckContext& ctx) {
  std::vector<std::function<SamplerChi2Result(int64_t, uint64_t)>> configs;
  std::vector<std::string> labels;
  struct Config {
    std::string kind;
    bool two_sided, point_variant;
  };
  for (const Config& c : {Config{"sphere", false, false}, Config{"rectangle", false, false}, Config{"disk", true, false},
                          Config{"mesh", false, false}, Config{"cylinder", false, false},
                          Config{"paraboloid", false, false}, Config{"torus", false, false},
                          Config{"mesh", false, true}, Config{"torus", false, true}}) {
    labels.push_back(c.kind + (c.two_sided ? " (two-sided)" : "") + (c.point_variant ? ", sample_li_point" : ""));
    configs.push_back([c](int64_t n, uint64_t seed) {
      const LightFixture f = make_fixture(c.kind, c.two_sided);
      return sample_li_chi2(f, Vec3(0.05, -0.02, 0.1), n, seed, 1, false, c.point_variant);
    });
  }
  return chi2_configs(ctx, "light.area.sample_li.chi2", configs, labels, 200000, 2000000);
}

CheckResult run_negative_control(const CheckContext& ctx) {
  // The rectangle light's NEE density stated without the 1/|cos theta_light| of the
  // area-to-solid-angle conversion must be rejected.
  const LightFixture f = make_fixture("rectangle", false);
  const Vec3 ref(0.05, -0.02, 0.1);
  const int64_t n = ctx.size(200000, 2000000);
  const SamplerChi2Result res = sample_li_chi2(f, ref, n, ctx.seed, 2, /*drop_cos=*/true);
  CheckResult r;
  r.passed = !res.passed(kAlpha);
  r.alpha = kAlpha;
  r.statistic_name = "p (must reject)";
  r.statistic = res.p_value();
  r.p_value = res.p_value();
  r.samples = res.samples;
  r.details = res.details();
  r.message = fmt::format("pdf without 1/|cos theta_light|: {} ({})", r.passed ? "rejected" : "NOT rejected", res.message());
  return r;
}

CheckResult run_emission_chi2(const CheckContext& ctx) {
  std::vector<std::function<SamplerChi2Result(int64_t, uint64_t)>> configs;
  std::vector<std::string> labels;
  for (bool two_sided : {false, true}) {
    labels.push_back(two_sided ? "rectangle two-sided" : "rectangle one-sided");
    configs.push_back([two_sided](int64_t n, uint64_t seed) {
      const LightFixture f = make_fixture("rectangle", two_sided);
      // In the emitter's normal frame, so the hemisphere boundary is a cell edge.
      const Frame frame = Frame::from_z(f.scene->sample_area(0, Vec2(0.5)).hit.n);
      return chi2_test(
          two_sided ? Chi2Domain::sphere(101, 50) : Chi2Domain::hemisphere(),
          [&](Uniforms& u) -> std::optional<Vec3> {
            const Vec2 up = u.next2();
            const auto s = f.light->sample_le(up, u.next2());
            if (!s) return std::nullopt;
            return frame.to_local(s->ray.d);
          },
          [&](const Vec3& w) { return pdf_emission_direction(frame.n, two_sided, frame.to_world(w)); },
          SamplerChi2Options{.samples = n, .seed = seed, .key = 3});
    });
  }
  labels.push_back("spot 40/25 degrees");
  configs.push_back([](int64_t n, uint64_t seed) {
    const Vec3 axis = glm::normalize(Vec3(0.3, -0.5, 1.0));
    const SpotLight spot(Vec3(0.0), axis, Rgb(1.0), 40.0, 25.0);
    const Frame frame = Frame::from_z(axis);
    Chi2Domain cap = Chi2Domain::sphere(101, 51);
    cap.y_min = std::cos(40.0 * kPi / 180.0);  // the cone is the domain: its rim is a cell edge
    return chi2_test(
        cap,
        [&](const Vec2& u) -> std::optional<Vec3> {
          const auto s = spot.sample_le(Vec2(0.5), u);
          if (!s) return std::nullopt;
          return frame.to_local(s->ray.d);
        },
        [&](const Vec3& w) {
          double pp, pd;
          spot.pdf_le(Hit{}, frame.to_world(w), &pp, &pd);
          return pd;
        },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 4});
  });
  labels.push_back("constant environment (sample_li)");
  configs.push_back([](int64_t n, uint64_t seed) {
    const ConstantEnvironmentLight env(Rgb(1.0));
    return chi2_test(
        Chi2Domain::sphere(),
        [&](const Vec2& u) -> std::optional<Vec3> { return env.sample_li(Vec3(0.0), u)->wi; },
        [&](const Vec3& w) { return env.pdf_li(Vec3(0.0), w, nullptr); },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 5});
  });
  labels.push_back("point light (sample_le direction)");
  configs.push_back([](int64_t n, uint64_t seed) {
    const Vec3 pos(0.3, -0.1, 0.2);
    const PointLight point(pos, Rgb(1.0));
    return chi2_test(
        Chi2Domain::sphere(),
        [&](Uniforms& u) -> std::optional<Vec3> {
          const Vec2 up = u.next2();
          const auto s = point.sample_le(up, u.next2());
          if (!s) return std::nullopt;
          // The origin must be the light's position; otherwise the sample is put off the sphere.
          return s->ray.o == pos ? s->ray.d : Vec3(2.0);
        },
        [&](const Vec3& w) {
          double pp, pd;
          point.pdf_le(Hit{}, w, &pp, &pd);
          return pd;
        },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 6});
  });
  // Infinite lights emit from the disk of the scene sphere's radius R centred at c - R w,
  // perpendicular to the direction of travel w (infinite_lights.h). The origin is binned in the
  // disk's polar chart (rho^2 / R^2, phi / 2 pi), in which the disk's rim is the domain boundary
  // and dA = pi R^2 d(rho^2/R^2) d(phi/2pi): p(chart) = pdf_pos * pi R^2. An origin off the disk's
  // plane, or (directional light) a direction other than w, is put outside the chart.
  const SceneSphere sphere{Vec3(0.4, -0.3, 0.2), 2.5};
  auto disk_chart = [sphere](const Vec3& w, const Vec3& o) -> Vec2 {
    const Frame fr = Frame::from_z(w);
    const Vec3 q = fr.to_local(o - (sphere.center - sphere.radius * w));
    if (std::abs(q.z) > 1e-9 * sphere.radius) return Vec2(-1.0);
    const double s = (q.x * q.x + q.y * q.y) / (sphere.radius * sphere.radius);
    return Vec2(std::min(s, 1.0), spherical_phi(Vec3(q.x, q.y, 0.0)) / (2.0 * kPi));
  };
  const Chi2Domain unit_square = Chi2Domain::rectangle(Vec2(0.0), Vec2(1.0), 41, 41);
  labels.push_back("directional light (sample_le position on the emission disk)");
  configs.push_back([=](int64_t n, uint64_t seed) {
    const Vec3 w = glm::normalize(Vec3(-0.4, 0.7, -1.0));
    DirectionalLight dir(w, Rgb(1.0));
    dir.set_scene_sphere(sphere);
    return chi2_test(
        unit_square,
        [&](Uniforms& u) -> std::optional<Vec2> {
          const Vec2 up = u.next2();
          const auto s = dir.sample_le(up, u.next2());
          if (!s) return std::nullopt;
          if (glm::length(s->ray.d - w) > 1e-12) return Vec2(-1.0);  // the fixed direction
          return disk_chart(w, s->ray.o);
        },
        [&](const Vec2&) {
          double pp, pd;
          dir.pdf_le(Hit{}, w, &pp, &pd);
          return pp * kPi * sphere.radius * sphere.radius;
        },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 7});
  });
  labels.push_back("constant environment (sample_le direction)");
  configs.push_back([=](int64_t n, uint64_t seed) {
    ConstantEnvironmentLight env(Rgb(1.0));
    env.set_scene_sphere(sphere);
    return chi2_test(
        Chi2Domain::sphere(),
        [&](Uniforms& u) -> std::optional<Vec3> {
          const Vec2 up = u.next2();
          const auto s = env.sample_le(up, u.next2());
          if (!s) return std::nullopt;
          return disk_chart(s->ray.d, s->ray.o).x >= 0.0 ? s->ray.d : Vec3(2.0);
        },
        [&](const Vec3& w) {
          double pp, pd;
          env.pdf_le(Hit{}, w, &pp, &pd);
          return pd;
        },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 8});
  });
  labels.push_back("constant environment (sample_le position on the emission disk)");
  configs.push_back([=](int64_t n, uint64_t seed) {
    ConstantEnvironmentLight env(Rgb(1.0));
    env.set_scene_sphere(sphere);
    return chi2_test(
        unit_square,
        [&](Uniforms& u) -> std::optional<Vec2> {
          const Vec2 up = u.next2();
          const auto s = env.sample_le(up, u.next2());
          if (!s) return std::nullopt;
          return disk_chart(s->ray.d, s->ray.o);
        },
        [&](const Vec2&) {
          double pp, pd;
          env.pdf_le(Hit{}, Vec3(0, 0, 1), &pp, &pd);
          return pp * kPi * sphere.radius * sphere.radius;
        },
        SamplerChi2Options{.samples = n, .seed = seed, .key = 9});
  });
  return chi2_configs(ctx, "light.emission.chi2", configs, labels, 200000, 2000000);
}

// Irradiance at a point on the axis of a one-sided disk light of radius R at height h facing
// it: E = pi Le R^2 / (R^2 + h^2) (the disk subtends a cone of sin^2 = R^2 / (R^2 + h^2)).
// Next-event estimation Le cos_ref / pdf_w must be unbiased for it. Negative control: the
// same estimator with the cos of the light dropped from the density must be rejected.
CheckResult run_nee_irradiance(const CheckContext& ctx, bool broken) {
  const double R = 0.8, h = 1.3, le = 2.0;
  Scene scene;
  const uint32_t id = scene.add(ShapeInstance(std::make_shared<Disk>(R), AffineTransform::translate(Vec3(0, 0, h)) *
                                                                            AffineTransform::rotate(kPi, Vec3(1, 0, 0))));
  scene.commit();
  const AreaLight light(scene, id, Rgb(le), false);
  const double exact = kPi * le * R * R / (R * R + h * h);
  const int64_t batches = 256, per_batch = ctx.size(1024, 16384);
  std::vector<double> means(static_cast<size_t>(batches));
  parallel_for(static_cast<size_t>(batches), [&](size_t b) {
    Rng rng = Rng::for_sample(ctx.seed, hash_string(broken ? "nee-broken" : "nee"), b);
    CompensatedSum s;
    for (int64_t i = 0; i < per_batch; ++i) {
      const auto ls = light.sample_li(Vec3(0.0), rng.uniform2());
      if (!ls) continue;
      double pdf = ls->pdf;
      if (broken) pdf *= std::abs(glm::dot(ls->n_light, ls->wi));
      s += ls->li.r * std::max(0.0, ls->wi.z) / pdf;
    }
    means[b] = s.value() / static_cast<double>(per_batch);
  });
  Welford w;
  for (double m : means) w.add(m);
  const double alpha = 1e-5;  // docs/validation.md A: analytic integrals at alpha = 1e-5
  const TestResult t = one_sample_t_test(w, exact);
  CheckResult r;
  const bool rejects = t.p_value < alpha;
  r.passed = broken ? rejects : !rejects;
  r.alpha = alpha;
  r.statistic_name = "t";
  r.statistic = t.statistic;
  r.p_value = t.p_value;
  r.samples = batches * per_batch;
  r.details = {{"exact", exact}, {"estimate", w.mean()}, {"std_error", w.std_error()},
               {"min_detectable_bias_90", minimal_detectable_bias(w.std_error(), alpha)}};
  r.message = fmt::format("{}E = {:.6f} ± {:.2e} vs exact {:.6f} (p = {:.3g}){}", broken ? "broken pdf: " : "",
                          w.mean(), w.std_error(), exact, t.p_value,
                          broken ? (rejects ? ", rejected as it must be" : ", NOT rejected") : "");
  return r;
}

TB_REGISTER_CHECK({.name = "light.area.sample_li.chi2",
                   .description = "Next-event sampling of area lights (sphere, rectangle, two-sided disk, triangle mesh, cylinder, "
                                  "paraboloid, torus; sample_li and sample_li_point) against the stated pdf_li (solid angle), "
                                  "binning the returned point in the emitter's chart, by chi-square",
                   .kind = CheckKind::kStatistical,
                   .run = run_sample_li_chi2});
TB_REGISTER_CHECK({.name = "light.area.sample_li.negative_control",
                   .description = "The chi-square test rejects an area light density missing 1/|cos theta_light|",
                   .kind = CheckKind::kStatistical,
                   .run = run_negative_control});
TB_REGISTER_CHECK({.name = "light.emission.chi2",
                   .description = "Emission sampling (one- and two-sided area light and spot light directions, point light "
                                  "direction, directional and environment emission-disk positions and directions) and "
                                  "environment next-event directions against their stated densities",
                   .kind = CheckKind::kStatistical,
                   .run = run_emission_chi2});
TB_REGISTER_CHECK({.name = "light.area.nee_irradiance",
                   .description = "Next-event estimate of the irradiance below a disk light equals pi Le R^2/(R^2+h^2) "
                                  "(t-test of 256 batch means, alpha 1e-5)",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_nee_irradiance(c, false); }});
TB_REGISTER_CHECK({.name = "light.area.nee_irradiance.negative_control",
                   .description = "The irradiance t-test rejects next-event estimation with a density that has an "
                                  "extra cos theta_light",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_nee_irradiance(c, true); }});

}  // namespace
}  // namespace tb

// Emitters: next-event sampling (sample_li) and emission sampling (sample_le) against their
// stated solid-angle densities (chi-square, docs/validation.md A), unbiasedness of next-event
// estimation of irradiance against a closed form, and a negative control.
#include <memory>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/geometry/disk.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/rectangle.h"
#include "lib/geometry/scene.h"
#include "lib/geometry/spawn.h"
#include "lib/geometry/sphere.h"
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

// One emitter in an otherwise empty scene, so that a direction from the reference point
// determines the light point by a ray query.
struct LightFixture {
  std::unique_ptr<Scene> scene = std::make_unique<Scene>();
  std::unique_ptr<AreaLight> light;
  std::string label;
};

LightFixture make_fixture(const std::string& kind, bool two_sided) {
  LightFixture f;
  f.label = kind + (two_sided ? " (two-sided)" : "");
  uint32_t id = 0;
  if (kind == "sphere") {
    id = f.scene->add(ShapeInstance(std::make_shared<Sphere>(0.5), AffineTransform::translate(Vec3(0.3, -0.2, 2.0))));
  } else if (kind == "rectangle") {
    // Tilted, facing the origin side (normal +z rotated by 150 degrees about x: mostly -z).
    id = f.scene->add(ShapeInstance(std::make_shared<Rectangle>(0.6, 0.3),
                                    AffineTransform::translate(Vec3(0.0, 0.4, 1.5)) *
                                        AffineTransform::rotate(150.0 * kPi / 180.0, Vec3(1, 0, 0))));
  } else if (kind == "disk") {
    id = f.scene->add(ShapeInstance(std::make_shared<Disk>(0.7), AffineTransform::translate(Vec3(0.2, 0.1, -1.2))));
  } else {  // "mesh": a quad as two triangles, tilted
    const TriangleMesh quad = make_quad_mesh(0.5, 0.4);
    const AffineTransform xf = AffineTransform::translate(Vec3(-0.3, 0.2, 1.0)) * AffineTransform::rotate(2.5, Vec3(1, 1, 0));
    std::vector<Vec3> p;
    for (const Vec3& q : quad.positions()) p.push_back(xf.point(q));
    id = f.scene->add(TriangleMesh(p, quad.triangles()));
  }
  f.scene->commit();
  f.light = std::make_unique<AreaLight>(*f.scene, id, Rgb(1.0), two_sided);
  return f;
}

// Next-event sampling is tested in the emitter's own (u, v) chart, where the emitter's outline is
// the domain boundary (no grid cell is cut by a silhouette): each sample is mapped to the (u, v)
// of the point it chose, and the stated solid-angle density pdf_li is carried to (u, v) measure
// with the Jacobian computed here, independently of the light code:
//   p(u, v) = pdf_li(ref, wi, hit) * |cos theta_light| / d^2 * |dp/du x dp/dv|.
// A pdf_li missing its 1/|cos theta_light| (the negative control) shows up as a wrong p(u, v).
SamplerChi2Result sample_li_chi2(const LightFixture& f, const Vec3& ref, int64_t n, uint64_t seed, uint64_t key,
                                 bool drop_cos) {
  SamplerChi2Options opt{.samples = n, .seed = seed, .key = key};
  return chi2_test(
      Chi2Domain::rectangle(Vec2(0.0), Vec2(1.0), 41, 41),
      [&](const Vec2& u) -> std::optional<Vec2> {
        const auto s = f.light->sample_li(ref, u);
        if (!s) return std::nullopt;
        return f.scene->sample_area(0, u).hit.uv;  // the same uniforms choose the same point
      },
      [&](const Vec2& uv) {
        const Hit h = f.scene->surface_at(0, 0, uv);
        const Vec3 d = h.p - ref;
        const double dist2 = glm::dot(d, d);
        const Vec3 wi = d / std::sqrt(dist2);
        const double cos_l = std::abs(glm::dot(h.n, wi));
        double pdf_w = f.light->pdf_li(ref, wi, &h);
        if (drop_cos) pdf_w *= cos_l;
        return pdf_w * cos_l / dist2 * glm::length(glm::cross(h.dpdu, h.dpdv));
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
  for (auto [kind, two_sided] :
       {std::pair{std::string("sphere"), false}, {std::string("rectangle"), false}, {std::string("disk"), true}}) {
    labels.push_back(kind + (two_sided ? " (two-sided)" : ""));
    configs.push_back([kind, two_sided](int64_t n, uint64_t seed) {
      const LightFixture f = make_fixture(kind, two_sided);
      return sample_li_chi2(f, Vec3(0.05, -0.02, 0.1), n, seed, 1, false);
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
                   .description = "Next-event sampling of area lights (sphere, rectangle, two-sided disk) against the stated pdf_li "
                                  "(solid angle), carried to the emitter's (u, v) chart, by chi-square",
                   .kind = CheckKind::kStatistical,
                   .run = run_sample_li_chi2});
TB_REGISTER_CHECK({.name = "light.area.sample_li.negative_control",
                   .description = "The chi-square test rejects an area light density missing 1/|cos theta_light|",
                   .kind = CheckKind::kStatistical,
                   .run = run_negative_control});
TB_REGISTER_CHECK({.name = "light.emission.chi2",
                   .description = "Emission directions (one- and two-sided area lights, spot light) and environment "
                                  "directions against their stated solid-angle densities",
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

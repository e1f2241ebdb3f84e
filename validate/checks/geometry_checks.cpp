// Registered checks of lib/geometry (docs/geometry.md):
//   geometry.<shape>.self_intersection   rays spawned from the surface never re-hit it
//   geometry.<shape>.area_sampling.chi2  area sampling against its pdf, in (u, v)
//   geometry.<shape>.differentials       dp/du, dp/dv, dn/du, dn/dv against finite differences
// for every shape of reference_analytic_shapes() and a tessellated sphere ("mesh"), plus a
// negative control for each kind of check.
#include <cmath>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/reference_shapes.h"
#include "lib/geometry/self_intersection.h"
#include "validate/chi2/pearson_gof.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/geometry/differential_check.h"
#include "validate/registry.h"

namespace tb {
namespace {

// Chi-square checks: alpha = 0.01 over all shape configurations (Sidak), docs/validation.md A.
double sidak(double alpha, size_t m) { return 1.0 - std::pow(1.0 - alpha, 1.0 / static_cast<double>(m)); }

TriangleMesh check_mesh() { return make_uv_sphere_mesh(1.7, 64, 128, Vec3(3.1, -2.3, 0.7)); }

// --- self-intersection ----------------------------------------------------------------------

CheckResult self_intersection_result(const SelfIntersectionStats& st, const std::string& what) {
  CheckResult r;
  r.passed = st.self_hits == 0 && st.leaks == 0;
  r.statistic_name = "self-intersections + leaks";
  r.statistic = static_cast<double>(st.self_hits + st.leaks);
  r.samples = st.rays;
  r.message = fmt::format("{}: {} self-intersections, {} leaks in {} rays{}", what, st.self_hits, st.leaks, st.rays,
                          st.first_bad >= 0 ? fmt::format(" (first bad ray index {})", st.first_bad) : "");
  r.details = {{"self_hits", st.self_hits}, {"leaks", st.leaks}, {"rays", st.rays}, {"first_bad", st.first_bad}};
  return r;
}

CheckResult run_self_intersection(const ReferenceShape& s, const CheckContext& ctx, bool disable_offset) {
  Scene scene;
  const uint32_t id = scene.add(s.instance);
  scene.commit();
  SelfIntersectionOptions o;
  o.rays = ctx.size(100000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string("geometry.self_intersection." + s.name);
  o.closed = s.instance.shape().closed();
  o.convex = s.name.rfind("sphere", 0) == 0;
  o.size = s.scale;
  o.disable_offset = disable_offset;
  return self_intersection_result(count_self_intersections(scene, id, o), s.name);
}

CheckResult run_mesh_self_intersection(const CheckContext& ctx, bool disable_offset) {
  Scene scene;
  const uint32_t id = scene.add(check_mesh());
  scene.commit();
  SelfIntersectionOptions o;
  o.rays = ctx.size(100000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string("geometry.self_intersection.mesh");
  o.closed = o.convex = true;
  o.size = 2 * std::sqrt(3.0) * 1.7;
  o.self_distance = 1e-6;  // float triangles: spurious hits lie within the offset (~1e-6 of the size)
  o.disable_offset = disable_offset;
  return self_intersection_result(count_self_intersections(scene, id, o), "mesh (32,512 triangles)");
}

// --- area sampling ----------------------------------------------------------------------------

double uv_density(const ShapeInstance& s, const Vec2& uv) {
  // Density in the (u, v) measure: pdf_area * |dp/du x dp/dv|.
  const Hit h = s.surface_at(uv);
  return s.pdf_area(uv) * glm::length(glm::cross(h.dpdu, h.dpdv));
}

CheckResult chi2_result(const SamplerChi2Result& c, double alpha, const std::string& what) {
  CheckResult r;
  r.passed = c.passed(alpha);
  state_chi2_power(r, c, alpha);
  r.statistic_name = "chi2";
  r.statistic = c.gof.statistic;
  r.p_value = c.p_value();
  r.alpha = alpha;
  r.samples = c.samples;
  r.message = what + ": " + c.message();
  r.details = c.details();
  r.plots.push_back(c.residual_heatmap(what + " (O - E) / sqrt(E) in (u, v)"));
  return r;
}

SamplerChi2Result shape_chi2(const ShapeInstance& s, const CheckContext& ctx, const std::string& key, bool broken) {
  SamplerChi2Options o;
  o.samples = ctx.size(200000, 1000000);
  o.seed = ctx.seed;
  o.key = hash_string(key);
  o.quadrature_tolerance = 1e-9;
  const int res = ctx.full ? 41 : 21;  // odd: no cell edge on the symmetry lines u, v = 1/2
  const Chi2Domain dom = Chi2Domain::rectangle({0, 0}, {1, 1}, res, res);
  if (broken)  // negative control: (u, v) uniform, i.e. the area element forgotten
    return chi2_test(dom, [](Vec2 u) { return u; }, [&](Vec2 uv) { return uv_density(s, uv); }, o);
  return chi2_test(
      dom, [&](Vec2 u) { return s.sample_area(u).hit.uv; }, [&](Vec2 uv) { return uv_density(s, uv); }, o);
}

CheckResult run_mesh_chi2(const CheckContext& ctx, double alpha) {
  // Triangle selection of the mesh sampler: counts per triangle against area / total area.
  const TriangleMesh mesh = make_uv_sphere_mesh(1.0, 8, 12);
  const int64_t n = ctx.size(200000, 1000000);
  std::vector<double> counts(mesh.triangle_count(), 0.0), expected;
  const uint64_t key = hash_string("geometry.mesh.area_sampling.chi2");
  for (int64_t i = 0; i < n; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, key, static_cast<uint64_t>(i));
    counts[mesh.sample_area(rng.uniform2()).hit.prim_id] += 1;
  }
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    expected.push_back(static_cast<double>(n) * mesh.triangle_area(t) / mesh.area());
  const PearsonResult g = pearson_chi2_gof(counts, expected);
  CheckResult r;
  r.passed = !g.rejects(alpha);
  r.statistic_name = "chi2";
  r.statistic = g.statistic;
  r.p_value = g.p_value;
  r.alpha = alpha;
  r.samples = n;
  r.message = "mesh triangle selection (" + std::to_string(mesh.triangle_count()) + " triangles): " + g.message;
  r.details = {{"dof", g.dof}, {"p_value", g.p_value}};
  return r;
}

// --- differentials ------------------------------------------------------------------------------

Vec2 interior_uv(uint64_t seed, uint64_t key, int64_t i) {
  Rng r = Rng::for_sample(seed, key, static_cast<uint64_t>(i));
  const double u = 0.01 + 0.98 * r.uniform();
  return {u, 0.01 + 0.98 * r.uniform()};
}

constexpr double kDifferentialTolerance = 1e-6;  // docs/validation.md C

CheckResult differentials_result(const std::function<Hit(const Vec2&)>& surface, const CheckContext& ctx,
                                 const std::string& what, double uv_scale) {
  const int64_t n = 1000;
  const uint64_t key = hash_string("geometry.differentials." + what);
  double worst = 0;
  int64_t worst_index = -1, skipped = 0;
  for (int64_t i = 0; i < n; ++i) {
    const DifferentialError e = check_differentials_at(surface, uv_scale * interior_uv(ctx.seed, key, i));
    if (e.skipped) {
      ++skipped;
      continue;
    }
    if (!(e.rel_error <= worst)) {
      worst = e.rel_error;
      worst_index = i;
    }
  }
  CheckResult r;
  r.passed = worst < kDifferentialTolerance && skipped < n;
  r.statistic_name = "max rel. error";
  r.statistic = worst;
  r.samples = n;
  r.message = fmt::format("{}: worst relative error {:.3g} (tolerance {:g}) at point {} of {}, {} skipped", what,
                          worst, kDifferentialTolerance, worst_index, n, skipped);
  r.details = {{"worst_rel_error", worst}, {"worst_index", worst_index}, {"skipped", skipped}};
  return r;
}

// --- registration -------------------------------------------------------------------------------

struct GeometryChecks {
  GeometryChecks() {
    auto& reg = Registry::global();
    const std::vector<ReferenceShape> shapes = reference_analytic_shapes();
    const double alpha = sidak(0.01, shapes.size() + 1);
    for (const ReferenceShape& s : shapes) {
      const auto shape = std::make_shared<ReferenceShape>(s);
      reg.add({.name = "geometry." + s.name + ".self_intersection",
               .description = "Rays spawned from " + s.name + " surface points (error-bound offsets) never re-hit it; "
                              "inward rays of closed shapes never escape",
               .kind = CheckKind::kDeterministic,
               .run = [shape](const CheckContext& ctx) { return run_self_intersection(*shape, ctx, false); }});
      reg.add({.name = "geometry." + s.name + ".area_sampling.chi2",
               .description = "Chi-square of " + s.name + " area sampling in (u, v) against pdf_area |dp/du x dp/dv|",
               .kind = CheckKind::kStatistical,
               .run = [shape, alpha](const CheckContext& ctx) {
                 return chi2_result(shape_chi2(shape->instance, ctx, "geometry.area_sampling." + shape->name, false),
                                    alpha, shape->name);
               }});
      reg.add({.name = "geometry." + s.name + ".differentials",
               .description = "dp/du, dp/dv, dn/du, dn/dv of " + s.name + " against central finite differences",
               .kind = CheckKind::kDeterministic,
               .run = [shape](const CheckContext& ctx) {
                 return differentials_result([&](const Vec2& uv) { return shape->instance.surface_at(uv); }, ctx,
                                             shape->name, 1.0);
               }});
    }
    reg.add({.name = "geometry.mesh.self_intersection",
             .description = "Rays spawned from a tessellated sphere never re-hit it (Embree float triangles)",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_mesh_self_intersection(ctx, false); }});
    reg.add({.name = "geometry.mesh.area_sampling.chi2",
             .description = "Chi-square of triangle selection by area in mesh area sampling",
             .kind = CheckKind::kStatistical,
             .run = [alpha](const CheckContext& ctx) { return run_mesh_chi2(ctx, alpha); }});
    reg.add({.name = "geometry.mesh.differentials",
             .description = "Mesh dp/du, dp/dv and interpolated-normal derivatives against finite differences",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               auto mesh = std::make_shared<TriangleMesh>(make_uv_sphere_mesh(1.3, 12, 16, Vec3(0.2, 0.1, -0.4)));
               CheckResult worst;
               worst.passed = true;
               for (uint32_t prim : {0u, 40u, 100u, 200u, static_cast<uint32_t>(mesh->triangle_count() - 1)}) {
                 CheckResult r = differentials_result([&](const Vec2& uv) { return mesh->surface_at(prim, uv); },
                                                      ctx, "mesh triangle " + std::to_string(prim), 0.5);
                 if (!r.passed || r.statistic >= worst.statistic) worst = r;
                 if (!worst.passed) break;
               }
               return worst;
             }});
    // Negative controls: each passes when the broken variant IS rejected.
    reg.add({.name = "geometry.self_intersection.negative_control",
             .description = "Without the error-bound offset, spawned rays self-intersect on the sphere, torus and mesh",
             .kind = CheckKind::kDeterministic,
             .run = [shapes](const CheckContext& ctx) {
               int64_t found = 0, cases = 0;
               std::string msg;
               for (const ReferenceShape& s : shapes) {
                 if (s.name != "sphere" && s.name != "torus") continue;
                 const CheckResult r = run_self_intersection(s, ctx, true);
                 found += r.statistic > 0;
                 ++cases;
                 msg += r.message + "; ";
               }
               const CheckResult m = run_mesh_self_intersection(ctx, true);
               found += m.statistic > 0;
               ++cases;
               CheckResult r;
               r.passed = found == cases;
               r.statistic_name = "cases with self-intersections";
               r.statistic = static_cast<double>(found);
               r.message = fmt::format("unoffset rays self-intersect in {} of {} cases: {}{}", found, cases, msg,
                                       m.message);
               return r;
             }});
    reg.add({.name = "geometry.area_sampling.chi2.negative_control",
             .description = "The chi-square check rejects uniform (u, v) sampling of the sphere and torus "
                            "(area element forgotten)",
             .kind = CheckKind::kStatistical,
             .run = [shapes, alpha](const CheckContext& ctx) {
               CheckResult out;
               out.passed = true;
               for (const ReferenceShape& s : shapes) {
                 if (s.name != "sphere" && s.name != "torus_aniso") continue;
                 const CheckResult r =
                     chi2_result(shape_chi2(s.instance, ctx, "geometry.area_sampling.neg." + s.name, true), alpha, s.name);
                 out.passed = out.passed && !r.passed;
                 out.samples += r.samples;
                 out.message += (r.passed ? "NOT rejected: " : "rejected: ") + r.message + "; ";
                 out.p_value = std::max(out.p_value, r.p_value);
               }
               out.statistic_name = "max p";
               out.statistic = out.p_value;
               out.alpha = alpha;
               return out;
             }});
    reg.add({.name = "geometry.differentials.negative_control",
             .description = "The finite-difference check rejects dn/du scaled by 1.01 on the torus",
             .kind = CheckKind::kDeterministic,
             .run = [shapes](const CheckContext& ctx) {
               const ReferenceShape* torus = nullptr;
               for (const ReferenceShape& s : shapes)
                 if (s.name == "torus_aniso") torus = &s;
               CheckResult r = differentials_result(
                   [&](const Vec2& uv) {
                     Hit h = torus->instance.surface_at(uv);
                     h.dndu *= 1.01;
                     return h;
                   },
                   ctx, "torus_aniso with dn/du * 1.01", 1.0);
               r.passed = !r.passed;
               r.message = (r.passed ? "rejected: " : "NOT rejected: ") + r.message;
               return r;
             }});
  }
};

const GeometryChecks kGeometryChecks;

}  // namespace
}  // namespace tb

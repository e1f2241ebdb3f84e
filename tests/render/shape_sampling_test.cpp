// Area sampling of every shape: the density integrates to one over the parameter square
// (quadrature of pdf_area |dp/du x dp/dv|), equals 1 / area for rigid placements, and the
// samples are uniform by area (chi-square in (u, v), validate/chi2).
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>

#include "lib/core/hash.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/reference_shapes.h"
#include "validate/chi2/sampler_chi2.h"

namespace tb {
namespace {

double uv_density(const ShapeInstance& s, const Vec2& uv) {
  const Hit h = s.surface_at(uv);
  return s.pdf_area(uv) * glm::length(glm::cross(h.dpdu, h.dpdv));
}

TEST(ShapeSampling, DensityIntegratesToOne) {
  using boost::math::quadrature::gauss_kronrod;
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    const double total = gauss_kronrod<double, 31>::integrate(
        [&](double v) {
          return gauss_kronrod<double, 31>::integrate([&](double u) { return uv_density(s.instance, {u, v}); }, 0.0,
                                                      1.0, 8, 1e-12);
        },
        0.0, 1.0, 8, 1e-12);
    EXPECT_NEAR(total, 1.0, 1e-9) << s.name;
  }
}

TEST(ShapeSampling, RigidPlacementIsUniformByArea) {
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    if (s.name.find("aniso") != std::string::npos) continue;
    for (double u : {0.1, 0.5, 0.93})
      EXPECT_NEAR(s.instance.pdf_area({u, 0.37}) * s.instance.shape().area(), 1.0, 1e-12) << s.name;
  }
}

TEST(ShapeSampling, ChiSquareInParameterSquare) {
  // alpha = 0.01 / 9 configurations (Sidak ~ Bonferroni), 2e5 samples, 21 x 21 cells.
  const auto shapes = reference_analytic_shapes();
  const double alpha = 0.01 / static_cast<double>(shapes.size());
  for (const ReferenceShape& s : shapes) {
    SamplerChi2Options opt;
    opt.samples = 200000;
    opt.key = hash_string("shape_sampling_test." + s.name);
    opt.quadrature_tolerance = 1e-8;
    const auto r = chi2_test(
        Chi2Domain::rectangle({0, 0}, {1, 1}, 21, 21), [&](Vec2 u) { return s.instance.sample_area(u).hit.uv; },
        [&](Vec2 uv) { return uv_density(s.instance, uv); }, opt);
    EXPECT_TRUE(r.passed(alpha)) << s.name << ": " << r.message();
  }
}

TEST(ShapeSampling, ChiSquareRejectsUniformParameterSampling) {
  // Negative control: sampling (u, v) uniformly (forgetting the area element) on the sphere,
  // tested against the area density.
  const auto shapes = reference_analytic_shapes();
  const ShapeInstance& sphere = shapes.front().instance;
  SamplerChi2Options opt;
  opt.samples = 200000;
  opt.key = hash_string("shape_sampling_test.negative");
  opt.quadrature_tolerance = 1e-8;
  const auto r = chi2_test(
      Chi2Domain::rectangle({0, 0}, {1, 1}, 21, 21), [&](Vec2 u) { return u; },
      [&](Vec2 uv) { return uv_density(sphere, uv); }, opt);
  EXPECT_FALSE(r.passed(0.01));
}

TEST(ShapeSampling, MeshSamplingIsUniformOverTriangles) {
  const TriangleMesh mesh = make_uv_sphere_mesh(1.0, 6, 8);
  std::vector<double> counts(mesh.triangle_count(), 0.0);
  const int n = 200000;
  Rng rng(3);
  for (int i = 0; i < n; ++i) {
    const AreaSample s = mesh.sample_area(rng.uniform2());
    EXPECT_GE(s.hit.uv.x, 0.0);
    EXPECT_GE(s.hit.uv.y, 0.0);
    EXPECT_LE(s.hit.uv.x + s.hit.uv.y, 1.0 + 1e-15);
    EXPECT_DOUBLE_EQ(s.pdf_area, 1.0 / mesh.area());
    counts[s.hit.prim_id] += 1;
  }
  std::vector<double> expected;
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) expected.push_back(n * mesh.triangle_area(t) / mesh.area());
  const PearsonResult g = pearson_chi2_gof(counts, expected);
  EXPECT_FALSE(g.rejects(1e-3)) << g.message;
}

}  // namespace
}  // namespace tb

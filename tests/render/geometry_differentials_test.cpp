// Differential geometry of every shape against finite differences of its parameterisation:
// dp/du, dp/dv, dn/du, dn/dv, plus consistency of normals and re-projection.
// (validate/stats/fd_jacobian.h crashed when this was written -- free() of an Eigen vector --
// so the geometry-specific checker validate/geometry/differential_check.h is used.)
#include <gtest/gtest.h>

#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/reference_shapes.h"
#include "validate/geometry/differential_check.h"

namespace tb {
namespace {

Vec2 interior_uv(int64_t i) {
  Rng r = Rng::for_sample(7, hash_string("geometry_differentials_test"), static_cast<uint64_t>(i));
  const double u = 0.02 + 0.96 * r.uniform();
  return {u, 0.02 + 0.96 * r.uniform()};
}

// Worst relative error over n seeded points; skipped points counted.
double worst_error(const std::function<Hit(const Vec2&)>& surface, int n, double uv_scale, int* skipped) {
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    const DifferentialError e = check_differentials_at(surface, uv_scale * interior_uv(i));
    if (e.skipped) {
      ++*skipped;
      continue;
    }
    worst = std::max(worst, e.rel_error);
  }
  return worst;
}

TEST(GeometryDifferentials, AnalyticShapesMatchFiniteDifferences) {
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    int skipped = 0;
    const double err = worst_error([&](const Vec2& uv) { return s.instance.surface_at(uv); }, 1000, 1.0, &skipped);
    EXPECT_LT(err, 1e-6) << s.name;
    EXPECT_EQ(skipped, 0) << s.name;
  }
}

TEST(GeometryDifferentials, PerturbedNormalDerivativeIsRejected) {
  // Negative control: dn/du off by 1% must exceed the tolerance.
  const auto shapes = reference_analytic_shapes();
  for (const ReferenceShape& s : shapes) {
    if (s.name != "torus_aniso" && s.name != "sphere") continue;
    int skipped = 0;
    const double err = worst_error(
        [&](const Vec2& uv) {
          Hit h = s.instance.surface_at(uv);
          h.dndu *= 1.01;
          return h;
        },
        100, 1.0, &skipped);
    EXPECT_GT(err, 1e-6) << s.name;
  }
}

TEST(GeometryDifferentials, MeshShadingNormalDerivatives) {
  const TriangleMesh mesh = make_uv_sphere_mesh(1.3, 12, 16, Vec3(0.2, 0.1, -0.4));
  for (uint32_t prim : {0u, 7u, 40u, 100u, static_cast<uint32_t>(mesh.triangle_count() - 1)}) {
    int skipped = 0;
    const double err = worst_error([&](const Vec2& uv) { return mesh.surface_at(prim, uv); }, 200, 0.5, &skipped);
    EXPECT_LT(err, 1e-6) << "prim " << prim;
  }
}

TEST(GeometryDifferentials, NormalIsOrthogonalToTangentsAndReprojectionIsIdentity) {
  for (const ReferenceShape& s : reference_analytic_shapes()) {
    for (int i = 0; i < 200; ++i) {
      const Vec2 uv = interior_uv(i);
      const Hit h = s.instance.surface_at(uv);
      const double tol = 1e-12;
      EXPECT_NEAR(glm::length(h.n), 1.0, tol) << s.name;
      EXPECT_NEAR(glm::dot(h.n, h.dpdu), 0.0, tol * glm::length(h.dpdu)) << s.name;
      EXPECT_NEAR(glm::dot(h.n, h.dpdv), 0.0, tol * glm::length(h.dpdv)) << s.name;
      EXPECT_NEAR(glm::dot(h.n, h.dndu), 0.0, 1e-10 * (1 + glm::length(h.dndu))) << s.name;
      const Vec2 back = s.instance.shape().project(s.instance.to_world().inverse_point(h.p));
      EXPECT_NEAR(back.x, uv.x, 1e-12) << s.name;
      EXPECT_NEAR(back.y, uv.y, 1e-12) << s.name;
    }
  }
}

}  // namespace
}  // namespace tb

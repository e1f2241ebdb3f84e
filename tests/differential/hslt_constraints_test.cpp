// Half-vector constraints (lib/differential/hslt_constraints.h, hslt_vertex.h): the tangent
// frame and its derivative, h^perp of known configurations, Eq. 11 against finite differences on
// sampled paths, and the measure forms Eq. 4 vs Eq. 5-7 (lib/differential/hslt_measure.h).
#include <cmath>
#include <limits>
#include <memory>

#include <gtest/gtest.h>

#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/differential/hslt_measure.h"
#include "lib/geometry/shape_instance.h"
#include "lib/geometry/sphere.h"
#include "validate/differential/hslt_paths.h"
#include "validate/stats/fd_jacobian.h"

namespace tb {
namespace {

ShapeInstance test_sphere() {
  return ShapeInstance(std::make_shared<Sphere>(0.7), AffineTransform::translate(Vec3(0.2, -0.1, 0.3)));
}

TEST(HsltVertex, FrameIsOrthonormalAndItsDerivativeMatchesFiniteDifferences) {
  const ShapeInstance s = test_sphere();
  const Vec2 uv(0.31, 0.62);
  const HsltVertex v = make_hslt_vertex(s.surface_at(uv));
  const HsltFrame f = hslt_frame(v);
  EXPECT_NEAR(glm::dot(f.s, f.t), 0.0, 1e-15);
  EXPECT_NEAR(glm::dot(f.s, f.n), 0.0, 1e-15);
  EXPECT_NEAR(glm::length(f.s), 1.0, 1e-15);
  EXPECT_NEAR(glm::dot(glm::cross(f.s, f.t), f.n), 1.0, 1e-15);
  const double h = 1e-6;
  for (int k = 0; k < 2; ++k) {
    Vec2 up = uv, um = uv;
    up[k] += h;
    um[k] -= h;
    const HsltFrame fp = hslt_frame(moved_hslt_vertex(v, s.surface_at(up)));
    const HsltFrame fm = hslt_frame(moved_hslt_vertex(v, s.surface_at(um)));
    EXPECT_LT(glm::length((fp.s - fm.s) / (2 * h) - f.ds[static_cast<size_t>(k)]), 1e-8);
    EXPECT_LT(glm::length((fp.t - fm.t) / (2 * h) - f.dt[static_cast<size_t>(k)]), 1e-8);
  }
}

TEST(HsltConstraints, MirrorAndSnellConfigurationsHaveZeroProjectedHalfVector) {
  // A vertex at the origin with normal +z (a flat surface point built by hand).
  HsltVertex x;
  x.dpdu = Vec3(1, 0, 0);
  x.dpdv = Vec3(0, 1, 0);
  x.frame_ref = Vec3(1, 0, 0);
  HsltPath p;
  p.vertices = {make_point_vertex(Vec3(-1, 0.5, 2)), x, make_point_vertex(Vec3(1, -0.5, 2))};
  EXPECT_LT(hslt_constraints(p).norm(), 1e-15);  // law of reflection
  // Refraction into eta = 1.5: sin(theta_t) = sin(theta_i) / 1.5.
  const double sin_i = 0.6, sin_t = sin_i / 1.5;
  p.vertices[1].eta_prev = 1.0;
  p.vertices[1].eta_next = 1.5;
  p.vertices[0] = make_point_vertex(Vec3(-sin_i, 0, std::sqrt(1 - sin_i * sin_i)));
  p.vertices[2] = make_point_vertex(Vec3(sin_t, 0, -std::sqrt(1 - sin_t * sin_t)) * 2.0);
  EXPECT_LT(hslt_constraints(p).norm(), 1e-15);
  // Off the specular configuration, h^perp is the tangential part of the unit half vector.
  p.vertices[2] = make_point_vertex(Vec3(0, 0, -1));
  const Vec3 H = Vec3(-sin_i, 0, std::sqrt(1 - sin_i * sin_i)) + 1.5 * Vec3(0, 0, -1);
  const Vec3 h = -H / glm::length(H);  // oriented to +z
  EXPECT_NEAR(hslt_constraints(p)[0], h.x, 1e-15);
  EXPECT_NEAR(hslt_constraints(p)[1], h.y, 1e-15);
}

TEST(HsltConstraints, JacobianMatchesFiniteDifferencesOnSampledPaths) {
  for (const char* family : {"mixed", "glass"}) {
    const HsltPathSet set = hslt_path_set(family, 6, 11);
    ASSERT_EQ(set.paths.size(), 6u);
    const Scene& scene = hslt_family_world(family).geometry();
    for (size_t i = 0; i < set.paths.size(); ++i) {
      const HsltPath& path = set.paths[i];
      const std::vector<int> free = hslt_free_vertices(path);
      const HsltFdChart chart = hslt_fd_chart(path, free);
      const stats::FdPointResult r = stats::check_jacobian_at(
          [&](const Eigen::VectorXd& x) { return chart.value(hslt_constraints(hslt_path_at(scene, path, free, chart.uv(x)))); },
          [&](const Eigen::VectorXd& x) {
            return chart.jacobian(hslt_free_columns(
                hslt_full_jacobian(hslt_constraint_blocks(hslt_path_at(scene, path, free, chart.uv(x)))), free));
          },
          Eigen::VectorXd::Zero(chart.uv0.size()), stats::FdOptions{.taylor_h0 = 0.1}, i);
      EXPECT_TRUE(r.passed) << family << " path " << i << ": err " << r.rel_error << " ridders " << r.ridders_rel_error
                            << " slope " << r.taylor_slope;
    }
  }
}

TEST(HsltMeasure, ProductOfJacobiansEqualsDirectFormAndReducesToEq7ForReflections) {
  const HsltPathSet set = hslt_path_set("reflection", 7, 3);
  ASSERT_EQ(set.paths.size(), 7u);
  for (const HsltPath& path : set.paths) {
    const HsltMeasureTerms t = hslt_measure_terms(path);
    ASSERT_TRUE(t.ok);
    EXPECT_NEAR(hslt_measure_product(t) / hslt_measure_direct(t), 1.0, 1e-9);
    // Eq. 7: for a reflection |do/dh| = 4 |<o, h>|.
    for (int i = 1; i < path.segments(); ++i) {
      const HsltHalfVector hv = hslt_half_vector(path, i);
      EXPECT_NEAR(t.do_dh[static_cast<size_t>(i - 1)], 4 * std::abs(glm::dot(hv.w_next, hv.h)), 1e-12);
    }
  }
}

}  // namespace
}  // namespace tb

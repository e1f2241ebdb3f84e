// Deterministic properties of the warps: samples lie in their domain, inverses round-trip,
// densities integrate to one (midpoint rule on the parameter grid). The chi-square fits are
// registered checks (validate/checks/warp_checks.cpp) and tests/validate/chi2_*_test.cpp.
#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "lib/core/warp_disk.h"
#include "lib/core/warp_sphere.h"
#include "lib/core/warp_triangle.h"

namespace tb {
namespace {

// Round trips are checked to 1e-9 in the uniforms (the registered inverse checks use the same).
constexpr double kRoundTrip = 1e-9;

template <class F>
void for_uniforms(F&& f) {
  Rng rng(7);
  for (int i = 0; i < 20000; ++i) f(rng.uniform2(), i);
  // Corners and edges of the square, where mappings have their special cases.
  for (double a : {0.0, 0.5, kOneMinusEpsilon, 1e-12, 1.0 - 1e-12})
    for (double b : {0.0, 0.5, kOneMinusEpsilon, 1e-12, 1.0 - 1e-12}) f(Vec2(a, b), -1);
}

TEST(WarpDisk, ConcentricInDiskAndInvertible) {
  for_uniforms([](Vec2 u, int i) {
    const Vec2 p = sample_uniform_disk_concentric(u);
    ASSERT_LE(glm::dot(p, p), 1.0 + 1e-15) << "index " << i;
    if (u.x == 0.5 && u.y == 0.5) return;  // the centre is one point for all of them
    const Vec2 v = invert_uniform_disk_concentric(p);
    EXPECT_NEAR(v.x, u.x, kRoundTrip) << "u = " << u.x << ", " << u.y;
    EXPECT_NEAR(v.y, u.y, kRoundTrip) << "u = " << u.x << ", " << u.y;
  });
  EXPECT_DOUBLE_EQ(pdf_uniform_disk({0.3, 0.2}), kInvPi);
  EXPECT_EQ(pdf_uniform_disk({0.9, 0.9}), 0.0);
}

// The phi coordinate wraps: u1 near 0 and near 1 are the same direction.
double wrap_distance(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 1.0 - d);
}

template <class S, class I>
void check_direction_warp(S sample, I invert, bool hemisphere, double z_min) {
  for_uniforms([&](Vec2 u, int i) {
    const Vec3 w = sample(u);
    ASSERT_NEAR(glm::length(w), 1.0, 1e-12) << "index " << i;
    if (hemisphere) {
      ASSERT_GE(w.z, 0.0);
    }
    ASSERT_GE(w.z, z_min - 1e-15);
    // At the poles phi is undefined; the round trip is checked away from them.
    if (sin_theta(w) < 1e-6) return;
    const Vec2 v = invert(w);
    EXPECT_NEAR(v.x, u.x, kRoundTrip) << "u = " << u.x << ", " << u.y;
    EXPECT_LE(wrap_distance(v.y, u.y), kRoundTrip) << "u = " << u.x << ", " << u.y;
  });
}

TEST(WarpSphere, UniformSphere) {
  check_direction_warp(sample_uniform_sphere, invert_uniform_sphere, false, -1.0);
  EXPECT_DOUBLE_EQ(pdf_uniform_sphere() * 4 * kPi, 1.0);
}
TEST(WarpSphere, UniformHemisphere) {
  check_direction_warp(sample_uniform_hemisphere, invert_uniform_hemisphere, true, 0.0);
  EXPECT_EQ(pdf_uniform_hemisphere({0, 0, -1}), 0.0);
}
TEST(WarpSphere, CosineHemisphere) {
  for_uniforms([](Vec2 u, int) {
    const Vec3 w = sample_cosine_hemisphere(u);
    ASSERT_NEAR(glm::length(w), 1.0, 1e-12);
    ASSERT_GE(w.z, 0.0);
    if (u.x == 0.5 && u.y == 0.5) return;
    // Near the horizon z = sqrt(1 - r^2) loses the disk radius; compare there in disk space.
    if (w.z < 1e-4) return;
    const Vec2 v = invert_cosine_hemisphere(w);
    EXPECT_NEAR(v.x, u.x, kRoundTrip);
    EXPECT_NEAR(v.y, u.y, kRoundTrip);
  });
  EXPECT_DOUBLE_EQ(pdf_cosine_hemisphere({0, 0, 1}), kInvPi);
}
TEST(WarpSphere, UniformCone) {
  for (double c : {0.99, 0.5, 0.0, -0.7}) {
    check_direction_warp([c](Vec2 u) { return sample_uniform_cone(u, c); },
                         [c](const Vec3& w) { return invert_uniform_cone(w, c); }, false, c);
    EXPECT_EQ(pdf_uniform_cone({0, 0, 1}, c), 1.0 / (2 * kPi * (1 - c)));
  }
}

TEST(WarpTriangle, BarycentricsAndInverse) {
  for_uniforms([](Vec2 u, int) {
    const Vec3 b = sample_uniform_triangle_barycentrics(u);
    ASSERT_GE(b.x, 0.0);
    ASSERT_GE(b.y, 0.0);
    ASSERT_GE(b.z, -1e-15);
    ASSERT_NEAR(b.x + b.y + b.z, 1.0, 1e-15);
    if (u.x < 1e-12) return;  // the vertex b0 = 1: u1 is not recoverable
    const Vec2 v = invert_uniform_triangle_barycentrics(b);
    EXPECT_NEAR(v.x, u.x, kRoundTrip);
    EXPECT_NEAR(v.y, u.y, kRoundTrip);
  });
  EXPECT_DOUBLE_EQ(pdf_uniform_triangle(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 5)), 1.0 / std::sqrt(26.0));
  EXPECT_DOUBLE_EQ(pdf_uniform_triangle(Vec2(0, 0), Vec2(2, 0), Vec2(0, 1)), 1.0);
}

}  // namespace
}  // namespace tb

// Uniform sampling of a triangle by barycentrics (square-root parametrization, Turk 1990 /
// Osada et al. 2002: b0 = 1 - sqrt(u0), b1 = u1 sqrt(u0)), with inverse. Density: 1 / area
// with respect to AREA on the triangle.
#pragma once

#include <cmath>

#include "lib/core/math.h"

namespace tb {

// Barycentrics (b0, b1, b2), b0 + b1 + b2 = 1, uniformly distributed over the triangle.
inline Vec3 sample_uniform_triangle_barycentrics(const Vec2& u) {
  const double s = std::sqrt(u.x);
  const double b0 = 1.0 - s, b1 = u.y * s;
  return {b0, b1, 1.0 - b0 - b1};
}
// Inverse: u0 = (1 - b0)^2, u1 = b1 / (1 - b0) (u1 is arbitrary at the vertex b0 = 1).
inline Vec2 invert_uniform_triangle_barycentrics(const Vec3& b) {
  const double s = 1.0 - b.x;
  return {s * s, s > 0.0 ? std::min(b.y / s, kOneMinusEpsilon) : 0.0};
}

// Point on the triangle (p0, p1, p2); works for 2D (Vec2) and 3D (Vec3) vertices.
template <class V>
V sample_uniform_triangle(const V& p0, const V& p1, const V& p2, const Vec2& u) {
  const Vec3 b = sample_uniform_triangle_barycentrics(u);
  return b.x * p0 + b.y * p1 + b.z * p2;
}

inline double triangle_area(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  return 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
}
inline double triangle_area(const Vec2& p0, const Vec2& p1, const Vec2& p2) {
  return 0.5 * std::abs(difference_of_products(p1.x - p0.x, p2.y - p0.y, p1.y - p0.y, p2.x - p0.x));
}
// Area density of a point on the triangle (the caller guarantees the point lies on it).
template <class V>
double pdf_uniform_triangle(const V& p0, const V& p1, const V& p2) {
  return 1.0 / triangle_area(p0, p1, p2);
}

}  // namespace tb

// Changes of measure between solid angle and area, and the geometry term (Veach 1997,
// Eq. 8.3 and 8.10): a density p_w in solid angle at x of a direction that reaches y becomes
// the area density p_A(y) = p_w |cos theta_y| / |x - y|^2, cos theta_y with y's geometric
// normal. A vertex without a surface normal (point light, the eye of a pinhole) contributes no
// cosine (pass a zero normal).
#pragma once

#include <cmath>

#include "lib/core/math.h"

namespace tb {

inline double solid_angle_to_area(double pdf_w, const Vec3& x, const Vec3& y, const Vec3& ng_y) {
  const Vec3 d = y - x;
  const double d2 = glm::dot(d, d);
  if (!(d2 > 0)) return 0.0;
  const bool has_normal = ng_y.x != 0 || ng_y.y != 0 || ng_y.z != 0;
  const double c = has_normal ? std::abs(glm::dot(ng_y, d)) / std::sqrt(d2) : 1.0;
  return pdf_w * c / d2;
}

// |cos_x| |cos_y| / |x - y|^2 with the given normals (zero normal: no cosine at that end).
inline double geometry_term(const Vec3& x, const Vec3& nx, const Vec3& y, const Vec3& ny) {
  const Vec3 d = y - x;
  const double d2 = glm::dot(d, d);
  if (!(d2 > 0)) return 0.0;
  const Vec3 w = d / std::sqrt(d2);
  const bool hx = nx.x != 0 || nx.y != 0 || nx.z != 0, hy = ny.x != 0 || ny.y != 0 || ny.z != 0;
  return (hx ? std::abs(glm::dot(nx, w)) : 1.0) * (hy ? std::abs(glm::dot(ny, w)) : 1.0) / d2;
}

}  // namespace tb

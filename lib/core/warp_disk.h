// Uniform sampling of the unit disk by the concentric mapping (Shirley & Chiu 1997, "A
// Low Distortion Map Between Disk and Square"), with its inverse. Density: 1/pi with respect
// to area on the unit disk.
#pragma once

#include <cmath>

#include "lib/core/math.h"

namespace tb {

// [0,1)^2 -> unit disk. Squares [-1,1]^2 concentric to the origin go to concentric circles,
// which keeps strata compact (Shirley & Chiu 1997, Sec. 3).
inline Vec2 sample_uniform_disk_concentric(const Vec2& u) {
  const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  double r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = kPiOver4 * (b / a);
  } else {
    r = b;
    phi = kPiOver2 - kPiOver4 * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

// Area density on the unit disk (zero outside).
inline double pdf_uniform_disk(const Vec2& p) { return glm::dot(p, p) <= 1.0 ? kInvPi : 0.0; }

// Unit disk -> [0,1]^2, the inverse of sample_uniform_disk_concentric. In the wedge
// |x| >= |y| the sample came from r = a, phi = pi/4 b/a, hence b = a * phi * 4/pi with
// phi = atan(y/x); in the other wedge r = b and pi/2 - phi = atan(x/y).
inline Vec2 invert_uniform_disk_concentric(const Vec2& p) {
  const double r = std::hypot(p.x, p.y);
  if (r == 0.0) return {0.5, 0.5};
  double a, b;
  if (std::abs(p.x) >= std::abs(p.y)) {
    a = std::copysign(r, p.x);
    b = a * std::atan(p.y / p.x) * (4.0 * kInvPi);
  } else {
    b = std::copysign(r, p.y);
    a = b * std::atan(p.x / p.y) * (4.0 * kInvPi);
  }
  return {0.5 * (a + 1.0), 0.5 * (b + 1.0)};
}

}  // namespace tb

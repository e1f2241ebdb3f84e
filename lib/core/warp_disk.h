// Uniform sampling of the unit disk by the concentric mapping (Shirley & Chiu 1997, "A
// Low Distortion Map Between Disk and Square"), with its inverse. Density: 1/pi with respect
// to area on the unit disk.
#pragma once

#include <cmath>

#include "lib/core/math.h"
#include "lib/core/sincos_quarter.h"

namespace tb {

// [0,1)^2 -> unit disk. Squares [-1,1]^2 concentric to the origin go to concentric circles,
// which keeps strata compact (Shirley & Chiu 1997, Sec. 3).
// The wedge angles phi = pi/4 * b/a and pi/2 - pi/4 * a/b lie within pi/4 of an axis, so sin and
// cos come from sincos_quarter (no libm call): cos(pi/2 - x) = sin x, sin(pi/2 - x) = cos x.
inline Vec2 sample_uniform_disk_concentric(const Vec2& u) {
  const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  // Selects rather than branches: the wedge is a coin flip for random u, so a branch would be
  // mispredicted half the time.
  const bool wedge_x = std::abs(a) > std::abs(b);
  const double r = select_bits(wedge_x, a, b);
  double s, c;
  sincos_quarter(kPiOver4 * (select_bits(wedge_x, b, a) / r), &s, &c);  // phi = pi/4 b/a or pi/2 - pi/4 a/b
  return {r * select_bits(wedge_x, c, s), r * select_bits(wedge_x, s, c)};
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

// Warps from [0,1)^2 to directions: uniform sphere, uniform hemisphere, cosine-weighted
// hemisphere (through the concentric disk, Malley's method) and uniform cone, each with its
// density in SOLID ANGLE and its inverse. Directions are in a local frame with +z the axis
// (hemisphere: z >= 0; cone: around +z).
#pragma once

#include <cmath>

#include "lib/core/frame.h"
#include "lib/core/math.h"
#include "lib/core/warp_disk.h"

namespace tb {

namespace warp_detail {
// phi in [0, 2 pi) -> u in [0, 1); a direction with phi exactly 2 pi - 0 maps to u < 1.
inline double phi_to_unit(const Vec3& w) { return std::min(spherical_phi(w) * kInv2Pi, kOneMinusEpsilon); }
}  // namespace warp_detail

// --- Uniform sphere: z = 1 - 2 u0, phi = 2 pi u1. Solid-angle density 1/(4 pi).
inline Vec3 sample_uniform_sphere(const Vec2& u) {
  const double z = 1.0 - 2.0 * u.x;
  return spherical_direction(safe_sqrt(1.0 - z * z), z, 2.0 * kPi * u.y);
}
inline double pdf_uniform_sphere() { return kInv4Pi; }
inline Vec2 invert_uniform_sphere(const Vec3& w) { return {0.5 * (1.0 - w.z), warp_detail::phi_to_unit(w)}; }

// --- Uniform hemisphere (z >= 0): z = u0, phi = 2 pi u1. Solid-angle density 1/(2 pi).
inline Vec3 sample_uniform_hemisphere(const Vec2& u) {
  const double z = u.x;
  return spherical_direction(safe_sqrt(1.0 - z * z), z, 2.0 * kPi * u.y);
}
inline double pdf_uniform_hemisphere(const Vec3& w) { return w.z >= 0.0 ? kInv2Pi : 0.0; }
inline Vec2 invert_uniform_hemisphere(const Vec3& w) { return {w.z, warp_detail::phi_to_unit(w)}; }

// --- Cosine-weighted hemisphere: a uniform point on the disk lifted to the hemisphere
// (Malley's method); solid-angle density cos(theta) / pi.
inline Vec3 sample_cosine_hemisphere(const Vec2& u) {
  const Vec2 d = sample_uniform_disk_concentric(u);
  return {d.x, d.y, safe_sqrt(1.0 - glm::dot(d, d))};
}
inline double pdf_cosine_hemisphere(const Vec3& w) { return w.z >= 0.0 ? w.z * kInvPi : 0.0; }
inline Vec2 invert_cosine_hemisphere(const Vec3& w) { return invert_uniform_disk_concentric({w.x, w.y}); }

// --- Uniform cone around +z with half-angle theta_max (cos_theta_max in [-1, 1)):
// cos(theta) = 1 - u0 (1 - cos_theta_max), phi = 2 pi u1; solid-angle density
// 1 / (2 pi (1 - cos_theta_max)) inside the cone.
inline Vec3 sample_uniform_cone(const Vec2& u, double cos_theta_max) {
  const double z = 1.0 - u.x * (1.0 - cos_theta_max);
  return spherical_direction(safe_sqrt(1.0 - z * z), z, 2.0 * kPi * u.y);
}
inline double pdf_uniform_cone(const Vec3& w, double cos_theta_max) {
  return w.z >= cos_theta_max ? 1.0 / (2.0 * kPi * (1.0 - cos_theta_max)) : 0.0;
}
inline Vec2 invert_uniform_cone(const Vec3& w, double cos_theta_max) {
  return {(1.0 - w.z) / (1.0 - cos_theta_max), warp_detail::phi_to_unit(w)};
}

}  // namespace tb

// Orthonormal frames. Local shading space has the normal along +z; cos(theta) = w.z.
#pragma once

#include "lib/core/math.h"

namespace tb {

// Builds a right-handed orthonormal basis (s, t, n) from a unit vector n without branches
// on near-parallel axes (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
inline void coordinate_system(const Vec3& n, Vec3* s, Vec3* t) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double b = n.x * n.y * a;
  *s = Vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
  *t = Vec3(b, sign + n.y * n.y * a, -n.y);
}

struct Frame {
  Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};

  Frame() = default;
  Frame(const Vec3& s_, const Vec3& t_, const Vec3& n_) : s(s_), t(t_), n(n_) {}
  static Frame from_z(const Vec3& n) {
    Frame f;
    f.n = n;
    coordinate_system(n, &f.s, &f.t);
    return f;
  }
  Vec3 to_local(const Vec3& v) const { return {glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

// Spherical-coordinate helpers for directions in a local frame.
inline double cos_theta(const Vec3& w) { return w.z; }
inline double abs_cos_theta(const Vec3& w) { return std::abs(w.z); }
inline double sin2_theta(const Vec3& w) { return std::max(0.0, 1.0 - w.z * w.z); }
inline double sin_theta(const Vec3& w) { return std::sqrt(sin2_theta(w)); }
inline double tan2_theta(const Vec3& w) { return sin2_theta(w) / (w.z * w.z); }
inline Vec3 spherical_direction(double sin_t, double cos_t, double phi) {
  return {std::clamp(sin_t, -1.0, 1.0) * std::cos(phi), std::clamp(sin_t, -1.0, 1.0) * std::sin(phi),
          std::clamp(cos_t, -1.0, 1.0)};
}
// phi in [0, 2 pi).
inline double spherical_phi(const Vec3& w) {
  const double p = std::atan2(w.y, w.x);
  return p < 0 ? p + 2 * kPi : p;
}

}  // namespace tb

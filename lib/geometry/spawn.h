// Robust spawning of rays from surfaces (pbrt-v3 Sec. 3.9, pbrt-v4 Sec. 6.8.6): the origin is
// moved along the geometric normal by the projection of the point's error box onto the normal,
// then rounded one ulp further away, so that the new ray cannot re-hit the surface it leaves.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "lib/core/math.h"
#include "lib/geometry/hit.h"
#include "lib/geometry/ray.h"

namespace tb {

// Bound on the relative error of n successive double operations (Higham's gamma_n).
constexpr double gamma_d(int n) { return (n * kEpsilon) / (1 - n * kEpsilon); }
// The same for float arithmetic (Embree's triangle intersector works in float).
constexpr double gamma_f(int n) {
  constexpr double eps_f = 0x1p-24;
  return (n * eps_f) / (1 - n * eps_f);
}

// The next representable double above / below v (std::nextafter towards +/- infinity, without
// the library call: pbrt-v4 NextFloatUp / NextFloatDown on the bit pattern).
inline double next_double_up(double v) {
  if (std::isinf(v) && v > 0) return v;
  if (v == 0.0) v = 0.0;  // -0 -> +0
  uint64_t bits = std::bit_cast<uint64_t>(v);
  bits = v >= 0 ? bits + 1 : bits - 1;
  return std::bit_cast<double>(bits);
}
inline double next_double_down(double v) {
  if (std::isinf(v) && v < 0) return v;
  if (v == 0.0) v = -0.0;  // +0 -> -0
  uint64_t bits = std::bit_cast<uint64_t>(v);
  bits = v > 0 ? bits - 1 : bits + 1;
  return std::bit_cast<double>(bits);
}

// pbrt-v4 OffsetRayOrigin: p moved out of its error box on the side of w, then rounded away.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& p_error, const Vec3& ng, const Vec3& w) {
  const double d = glm::dot(glm::abs(ng), p_error);
  Vec3 offset = d * ng;
  if (glm::dot(w, ng) < 0) offset = -offset;
  Vec3 po = p + offset;
  for (int i = 0; i < 3; ++i) {
    if (offset[i] > 0)
      po[i] = next_double_up(po[i]);
    else if (offset[i] < 0)
      po[i] = next_double_down(po[i]);
  }
  return po;
}

// A ray leaving the surface at `h` in direction w (any length).
inline Ray spawn_ray(const Hit& h, const Vec3& w) {
  Ray r;
  r.o = offset_ray_origin(h.p, h.p_error, h.ng, w);
  r.d = w;
  return r;
}

// A shadow ray from `h` towards the point p2: the target is at t = 1 and t_max is
// 1 - kShadowEpsilon, so Scene::occluded(ray) tests the open segment.
inline Ray spawn_ray_to(const Hit& h, const Vec3& p2) {
  Ray r;
  r.o = offset_ray_origin(h.p, h.p_error, h.ng, p2 - h.p);
  r.d = p2 - r.o;
  r.t_max = 1 - kShadowEpsilon;
  return r;
}

// A shadow ray between two surface points, both ends offset off their surfaces.
inline Ray spawn_ray_to(const Hit& from, const Hit& to) {
  const Vec3 pf = offset_ray_origin(from.p, from.p_error, from.ng, to.p - from.p);
  const Vec3 pt = offset_ray_origin(to.p, to.p_error, to.ng, pf - to.p);
  Ray r;
  r.o = pf;
  r.d = pt - pf;
  r.t_max = 1 - kShadowEpsilon;
  return r;
}

}  // namespace tb

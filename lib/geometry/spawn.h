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

// next_double_up(v) for dir > 0, next_double_down(v) for dir < 0, v for dir == 0 (or NaN), with
// no data-dependent branch for finite non-zero v: the step on the bit pattern is +-1 by the signs
// of dir and v. (Branches on the signs of the offset were mispredicted about half the time, since
// consecutive vertices lie on differently oriented surfaces.)
inline double next_double_toward(double v, double dir) {
  if (v == 0.0 || std::isinf(v)) [[unlikely]]
    return dir > 0 ? next_double_up(v) : (dir < 0 ? next_double_down(v) : v);
  const uint64_t bits = std::bit_cast<uint64_t>(v);
  const int64_t s_dir = static_cast<int64_t>(dir > 0) - static_cast<int64_t>(dir < 0);
  const int64_t s_v = 1 - 2 * static_cast<int64_t>(bits >> 63);  // +1 for v > 0, -1 for v < 0
  return std::bit_cast<double>(bits + static_cast<uint64_t>(s_dir * s_v));
}

// pbrt-v4 OffsetRayOrigin: p moved out of its error box on the side of w, then rounded away.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& p_error, const Vec3& ng, const Vec3& w) {
  const double d = glm::dot(abs_components(ng), p_error);
  Vec3 offset = d * ng;
  if (glm::dot(w, ng) < 0) offset = -offset;
  const Vec3 po = p + offset;
  return {next_double_toward(po.x, offset.x), next_double_toward(po.y, offset.y), next_double_toward(po.z, offset.z)};
}

// A ray leaving the surface at `h` in direction w (any length).
inline Ray spawn_ray(const SurfacePoint& h, const Vec3& w) {
  Ray r;
  r.o = offset_ray_origin(h.p, h.p_error, h.ng, w);
  r.d = w;
  return r;
}

// spawn_ray(h, w) written into *r field by field: a loop's ray variable assigned a returned Ray
// was copied with 16-byte loads over the 8-byte stores that built the temporary (store-forwarding
// stalls on every bounce of the path tracer).
inline void spawn_ray_into(const SurfacePoint& h, const Vec3& w, Ray* r) {
  r->o = offset_ray_origin(h.p, h.p_error, h.ng, w);
  r->d = w;
  r->t_min = 0.0;
  r->t_max = kInfinity;
}

// A shadow ray from `h` towards the point p2: the target is at t = 1 and t_max is
// 1 - kShadowEpsilon, so Scene::occluded(ray) tests the open segment.
inline Ray spawn_ray_to(const SurfacePoint& h, const Vec3& p2) {
  Ray r;
  r.o = offset_ray_origin(h.p, h.p_error, h.ng, p2 - h.p);
  r.d = p2 - r.o;
  r.t_max = 1 - kShadowEpsilon;
  return r;
}

// A shadow ray between two surface points, both ends offset off their surfaces.
inline Ray spawn_ray_to(const SurfacePoint& from, const SurfacePoint& to) {
  const Vec3 pf = offset_ray_origin(from.p, from.p_error, from.ng, to.p - from.p);
  const Vec3 pt = offset_ray_origin(to.p, to.p_error, to.ng, pf - to.p);
  Ray r;
  r.o = pf;
  r.d = pt - pf;
  r.t_max = 1 - kShadowEpsilon;
  return r;
}

}  // namespace tb

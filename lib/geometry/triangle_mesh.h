// Triangle meshes in world space, optionally with per-vertex shading normals and texture
// coordinates. Positions are rounded to float on construction, so that the double-precision
// geometry computed here is that of the very triangles Embree intersects.
//
// Parameterisation of a hit: uv = barycentric coordinates (b1, b2) within triangle prim_id,
// p = (1 - b1 - b2) p0 + b1 p1 + b2 p2; so dp/du = p1 - p0, dp/dv = p2 - p0. The shading normal
// is the normalised linear interpolation of the vertex normals, and dn/du, dn/dv are its exact
// derivatives (I - n n^T) (n1 - n0) / |n~| etc. Texture coordinates are an attribute
// (texcoord()), not the parameterisation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "lib/core/math.h"
#include "lib/geometry/area_sample.h"
#include "lib/geometry/bounds.h"
#include "lib/geometry/hit.h"
#include "lib/geometry/ray.h"

namespace tb {

class TriangleMesh {
 public:
  TriangleMesh(std::vector<Vec3> positions, std::vector<glm::uvec3> triangles, std::vector<Vec3> normals = {},
               std::vector<Vec2> texcoords = {}, bool flip_normal = false);

  size_t triangle_count() const { return tris_.size(); }
  const std::vector<Vec3>& positions() const { return pos_; }
  const std::vector<glm::uvec3>& triangles() const { return tris_; }
  bool has_normals() const { return !nrm_.empty(); }

  // Differential geometry at barycentrics uv = (b1, b2) of triangle `prim`.
  Hit surface_at(uint32_t prim, const Vec2& uv) const {
    Hit h;
    surface_at(prim, uv, &h);
    return h;
  }
  // The same, written into *h (every field of a Hit is set).
  void surface_at(uint32_t prim, const Vec2& uv, Hit* h) const;
  // Only the SurfacePoint fields (no derivatives), t = t_hit, shape_id = 0, written into *out
  // field by field: callers build their record where it is used (an optional's payload, a
  // Hit's base), because a SurfacePoint returned by value and then copied is read back with
  // 16-byte loads over the callee's 8-byte stores (store-forwarding stalls, ~40 % of
  // Scene::intersect_point's time before).
  void point_into(uint32_t prim, const Vec2& uv, double t_hit, SurfacePoint* out) const;
  // Re-intersects the double ray with triangle `prim` (plane intersection, barycentrics clamped
  // to the triangle): refines a float hit reported by Embree. Falls back to (t, uv) given.
  Hit refine_hit(uint32_t prim, const Ray& ray, double t_float, const Vec2& uv_float) const {
    Hit h;
    refine_hit(prim, ray, t_float, uv_float, &h);
    return h;
  }
  void refine_hit(uint32_t prim, const Ray& ray, double t_float, const Vec2& uv_float, Hit* h) const;
  Vec2 texcoord(uint32_t prim, const Vec2& uv) const;

  double area() const { return total_area_; }
  double triangle_area(uint32_t prim) const;
  // Uniform by area: triangle chosen by area (u.x, re-used), uniform barycentrics
  // (b0 = 1 - sqrt(s)); density 1 / area() per unit area.
  AreaSample sample_area(const Vec2& u) const;
  // The same point written into *h; returns its density per unit area.
  double sample_area(const Vec2& u, Hit* h) const;
  SurfacePoint sample_point(const Vec2& u, double* pdf_area) const;
  // Position and shading normal of the point sample_point(u) returns, bit for bit, without the
  // fields next-event estimation does not read (error bound, side of ng, ids): AreaLight samples
  // its mesh with this directly, not through Scene::sample_point. Density pdf_area().
  struct PositionNormal {
    Vec3 p, n;
  };
  // Defined inline below (the light-sampling chain of every next-event estimate runs through it);
  // GCC may still keep it out of line: forcing it inline into AreaLight made no measurable
  // difference.
  PositionNormal sample_position(const Vec2& u) const;
  double pdf_area() const { return 1.0 / total_area_; }

 private:
  std::vector<Vec3> pos_;
  std::vector<glm::uvec3> tris_;
  std::vector<Vec3> nrm_;
  std::vector<Vec2> uv_;
  // Per-triangle quantities that every hit on the triangle needs, computed once (the same
  // expressions surface_at and refine_hit would evaluate, so results are bit-identical).
  struct TriangleFrame {
    Vec3 ng{0.0};          // normalize(cross(p1 - p0, p2 - p0))
    Vec3 plane{0.0};       // cross(p1 - p0, p2 - p0)
    double d00 = 0, d01 = 0, d11 = 0, denom = 0;  // Gram matrix of (e1, e2) and its determinant
  };
  std::vector<TriangleFrame> frames_;
  // The two halves of point_into, shared with sample_position: the point b0 p0 + b1 p1 + b2 p2 of
  // triangle t, and the shading normal *n with the geometric normal *ng on its side (flip_
  // applied to both). Inlined so that sample_position drops the ng it does not use.
  Vec3 position(const glm::uvec3& t, double b0, double b1, double b2) const {
    return b0 * pos_[t[0]] + b1 * pos_[t[1]] + b2 * pos_[t[2]];
  }
  [[gnu::always_inline]] void normals(uint32_t prim, const glm::uvec3& t, double b0, double b1, double b2, Vec3* ng,
                                      Vec3* n) const;
  // Refined (t, barycentrics) of a float hit; uv_float / t_float when the ray is parallel.
  Vec2 refine_uv(uint32_t prim, const Ray& ray, double t_float, const Vec2& uv_float, double* t) const;
  // Triangle and barycentrics of an area sample (inlined: a few dozen instructions, called once per
  // light sample).
  [[gnu::always_inline]] uint32_t sample_uv(const Vec2& u, Vec2* uv) const;
  std::vector<double> cdf_;        // cumulative triangle areas, cdf_.back() == total_area_
  std::vector<double> inv_width_;  // 1 / (cdf_[i] - cdf_[i - 1]), 0 for a zero-area triangle
  double total_area_ = 0;
  bool flip_;
};

namespace detail {

// std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin() for a sorted cdf, with a loop whose
// trip count depends only on the size and a conditional move inside: for random x the branches of
// std::upper_bound are mispredicted about half the time.
inline size_t upper_bound_branchless(const std::vector<double>& cdf, double x) {
  size_t base = 0, len = cdf.size();
  while (len > 1) {
    const size_t half = len / 2;
    base = cdf[base + half - 1] <= x ? base + half : base;  // first half entirely <= x
    len -= half;
  }
  return base + (cdf[base] <= x ? 1 : 0);
}

}  // namespace detail

inline void TriangleMesh::normals(uint32_t prim, const glm::uvec3& t, double b0, double b1, double b2, Vec3* ng_out,
                                  Vec3* n_out) const {
  Vec3 ng = frames_[prim].ng, n = ng;
  if (!nrm_.empty()) {
    const Vec3 a = b0 * nrm_[t[0]] + b1 * nrm_[t[1]] + b2 * nrm_[t[2]];
    const double len = glm::length(a);
    if (len > 0) n = a / len;
    if (glm::dot(ng, n) < 0) ng = -ng;  // geometric normal on the side of the shading normal
  }
  if (flip_) {
    n = -n;
    ng = -ng;
  }
  *ng_out = ng;
  *n_out = n;
}

inline uint32_t TriangleMesh::sample_uv(const Vec2& u, Vec2* uv) const {
  const double target = u.x * total_area_;
  const size_t i = detail::upper_bound_branchless(cdf_, target);
  const uint32_t prim = static_cast<uint32_t>(std::min(i, cdf_.size() - 1));
  const double lo = select_bits(prim == 0, 0.0, cdf_[prim == 0 ? 0 : prim - 1]);  // no jump on prim
  // The re-used uniform (target - lo) / width, as a product with the stored reciprocal (within an
  // ulp of the quotient; 0 for a zero-width triangle, as before).
  const double s = std::clamp((target - lo) * inv_width_[prim], 0.0, 1.0);
  const double su = std::sqrt(s);
  *uv = {su * (1 - u.y), su * u.y};
  return prim;
}

inline TriangleMesh::PositionNormal TriangleMesh::sample_position(const Vec2& u) const {
  Vec2 uv;
  const uint32_t prim = sample_uv(u, &uv);
  const glm::uvec3 t = tris_[prim];
  const double b1 = uv.x, b2 = uv.y, b0 = 1 - b1 - b2;  // as in point_into
  Vec3 ng, n;
  normals(prim, t, b0, b1, b2, &ng, &n);  // ng unused: its side test is dead code here
  return {position(t, b0, b1, b2), n};
}

}  // namespace tb

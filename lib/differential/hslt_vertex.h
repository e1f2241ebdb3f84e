// The differential geometry of one path vertex for the half-vector constraint formulation
// (Kaplanyan, Hanika, Dachsbacher 2014, Sec. 4.2 and App. A): position, tangents dp/du, dp/dv,
// shading normal n and its derivatives dn/du, dn/dv, the refractive indices on both sides, and
// the smooth local tangent frame (s, t, n) in which the projected half vector h^perp is written.
//
// The frame. App. A writes h^perp in the tangent frame of the vertex (Table 1: (u, v, n)). For the
// constraint to be a smooth function of the vertex position whose derivative needs only first
// derivatives of the surface, the frame is a function of the shading normal alone:
//   s(n) = w / |w|,  w = a - n <n, a>,   t = n x s,
// with a fixed reference vector a (the unit dp/du of the vertex where the path was built, held
// constant when the vertex moves). At the build point s is the Gram-Schmidt direction of dp/du.
// Its derivatives along the surface follow from dn/du, dn/dv only:
//   dw = -dn <n, a> - n <dn, a>,  ds = (I - s s^T) dw / |w|,  dt = dn x s + n x ds.
// Any other smooth frame differs by a rotation R(u, v) of the (s, t) plane: h^perp and its
// Jacobian change by R, |det| does not.
#pragma once

#include <array>
#include <cstdint>

#include "lib/core/math.h"
#include "lib/geometry/hit.h"

namespace tb {

struct HsltVertex {
  Vec3 p{0.0};
  Vec3 dpdu{0.0}, dpdv{0.0};  // zero for a point endpoint (no surface parameterisation)
  Vec3 n{0, 0, 1};            // shading normal (unit): the frame normal of h^perp
  Vec3 ng{0, 0, 1};           // geometric normal (unit): foreshortening of the area measure
  Vec3 dndu{0.0}, dndv{0.0};
  Vec2 uv{0.0};
  uint32_t shape_id = 0, prim_id = 0;
  bool on_surface = true;     // false: a fixed point endpoint (pinhole camera, point light)
  // Refractive index of the medium on the side of the previous / next vertex of the path.
  // Equal for a reflection; eta_prev != eta_next for a refraction (App. A: eta = eta_o / eta_i).
  double eta_prev = 1.0, eta_next = 1.0;
  Vec3 frame_ref{1, 0, 0};    // the fixed reference a of the tangent frame (see above)

  // |dp/du x dp/dv|: area per unit (u, v).
  double area_element() const { return glm::length(glm::cross(dpdu, dpdv)); }
};

// A vertex on a surface from its Hit; the frame reference is the unit dp/du of this Hit.
inline HsltVertex make_hslt_vertex(const Hit& h, double eta_prev = 1.0, double eta_next = 1.0) {
  HsltVertex v;
  v.p = h.p;
  v.dpdu = h.dpdu;
  v.dpdv = h.dpdv;
  v.n = h.n;
  v.ng = h.ng;
  v.dndu = h.dndu;
  v.dndv = h.dndv;
  v.uv = h.uv;
  v.shape_id = h.shape_id;
  v.prim_id = h.prim_id;
  v.eta_prev = eta_prev;
  v.eta_next = eta_next;
  const double l = glm::length(h.dpdu);
  v.frame_ref = l > 0 ? h.dpdu / l : Vec3(1, 0, 0);
  return v;
}

// The same vertex moved to the surface point `h` (same shape): keeps the indices of refraction
// and the frame reference, so that the frame is the smooth function of (u, v) described above.
inline HsltVertex moved_hslt_vertex(const HsltVertex& v, const Hit& h) {
  HsltVertex m = make_hslt_vertex(h, v.eta_prev, v.eta_next);
  m.frame_ref = v.frame_ref;
  return m;
}

// A fixed point endpoint (pinhole camera, point light).
inline HsltVertex make_point_vertex(const Vec3& p, double eta = 1.0) {
  HsltVertex v;
  v.p = p;
  v.on_surface = false;
  v.eta_prev = v.eta_next = eta;
  return v;
}

// The tangent frame (s, t, n) of a vertex and its derivatives along u and v (index 0, 1).
struct HsltFrame {
  Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};
  std::array<Vec3, 2> ds{Vec3(0.0), Vec3(0.0)}, dt{Vec3(0.0), Vec3(0.0)};
};

inline HsltFrame hslt_frame(const HsltVertex& v) {
  HsltFrame f;
  f.n = v.n;
  const double na = glm::dot(v.n, v.frame_ref);
  const Vec3 w = v.frame_ref - v.n * na;
  const double lw = glm::length(w);
  f.s = w / lw;
  f.t = glm::cross(f.n, f.s);
  const std::array<Vec3, 2> dn{v.dndu, v.dndv};
  for (int k = 0; k < 2; ++k) {
    const Vec3 dw = -dn[k] * na - v.n * glm::dot(dn[k], v.frame_ref);
    f.ds[k] = (dw - f.s * glm::dot(f.s, dw)) / lw;
    f.dt[k] = glm::cross(dn[k], f.s) + glm::cross(f.n, f.ds[k]);
  }
  return f;
}

}  // namespace tb

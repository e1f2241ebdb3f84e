#include "lib/geometry/triangle_mesh.h"

#include <algorithm>
#include <stdexcept>

#include "lib/geometry/spawn.h"

namespace tb {

TriangleMesh::TriangleMesh(std::vector<Vec3> positions, std::vector<glm::uvec3> triangles, std::vector<Vec3> normals,
                           std::vector<Vec2> texcoords, bool flip_normal)
    : pos_(std::move(positions)), tris_(std::move(triangles)), nrm_(std::move(normals)), uv_(std::move(texcoords)),
      flip_(flip_normal) {
  if (!nrm_.empty() && nrm_.size() != pos_.size()) throw std::invalid_argument("TriangleMesh: one normal per vertex");
  if (!uv_.empty() && uv_.size() != pos_.size()) throw std::invalid_argument("TriangleMesh: one texcoord per vertex");
  for (Vec3& p : pos_) p = Vec3(glm::vec3(p));  // exactly Embree's float vertices
  for (const glm::uvec3& t : tris_)
    for (int k = 0; k < 3; ++k)
      if (t[k] >= pos_.size()) throw std::invalid_argument("TriangleMesh: vertex index out of range");
  frames_.reserve(tris_.size());
  for (const glm::uvec3& t : tris_) {
    const Vec3 e1 = pos_[t[1]] - pos_[t[0]], e2 = pos_[t[2]] - pos_[t[0]];
    TriangleFrame f;
    f.plane = glm::cross(e1, e2);
    f.ng = glm::normalize(f.plane);
    f.d00 = glm::dot(e1, e1);
    f.d01 = glm::dot(e1, e2);
    f.d11 = glm::dot(e2, e2);
    f.denom = difference_of_products(f.d00, f.d11, f.d01, f.d01);
    frames_.push_back(f);
  }
  cdf_.reserve(tris_.size());
  CompensatedSum sum;
  for (uint32_t i = 0; i < tris_.size(); ++i) {
    sum += triangle_area(i);
    cdf_.push_back(sum.value());
  }
  // 1 / (width of triangle i in the cdf): sample_uv re-uses u.x with a multiplication (a division
  // on the light-sampling chain of every next-event estimate otherwise). Zero for a zero width.
  inv_width_.reserve(tris_.size());
  for (size_t i = 0; i < cdf_.size(); ++i) {
    const double width = cdf_[i] - (i == 0 ? 0.0 : cdf_[i - 1]);
    inv_width_.push_back(width > 0 ? 1.0 / width : 0.0);
  }
  total_area_ = sum.value();
  if (!(total_area_ > 0)) throw std::invalid_argument("TriangleMesh: zero area");
}

double TriangleMesh::triangle_area(uint32_t prim) const {
  const glm::uvec3 t = tris_[prim];
  return 0.5 * glm::length(glm::cross(pos_[t[1]] - pos_[t[0]], pos_[t[2]] - pos_[t[0]]));
}

void TriangleMesh::point_into(uint32_t prim, const Vec2& uv, double t_hit, SurfacePoint* out) const {
  const glm::uvec3 t = tris_[prim];
  const Vec3 &p0 = pos_[t[0]], &p1 = pos_[t[1]], &p2 = pos_[t[2]];
  const double b1 = uv.x, b2 = uv.y, b0 = 1 - b1 - b2;
  normals(prim, t, b0, b1, b2, &out->ng, &out->n);
  // Embree intersects in float: the bound covers its float arithmetic on coordinates of this
  // magnitude (pbrt-v3 Sec. 3.9.6 uses gamma_7 for its own float test; we allow more for
  // Embree's different formulation and for the float rounding of the ray origin).
  // Isotropic: Embree's plane and edge tests mix all coordinates, so a triangle lying in z = 0
  // still needs an offset in z.
  const Vec3 mag = abs_components(b0 * p0) + abs_components(b1 * p1) + abs_components(b2 * p2);
  out->p_error = Vec3(gamma_f(32) * max_component(mag));
  out->p = position(t, b0, b1, b2);
  out->uv = uv;
  out->shape_id = 0u;
  out->prim_id = prim;
  out->t = t_hit;
}

void TriangleMesh::surface_at(uint32_t prim, const Vec2& uv, Hit* out) const {
  point_into(prim, uv, 0.0, out);
  const glm::uvec3 t = tris_[prim];
  const Vec3 &p0 = pos_[t[0]], &p1 = pos_[t[1]], &p2 = pos_[t[2]];
  Hit& h = *out;
  h.dpdu = p1 - p0;
  h.dpdv = p2 - p0;
  h.dndu = Vec3(0.0);
  h.dndv = Vec3(0.0);
  if (!nrm_.empty()) {
    const double b1 = uv.x, b2 = uv.y, b0 = 1 - b1 - b2;
    const Vec3 &n0 = nrm_[t[0]], &n1 = nrm_[t[1]], &n2 = nrm_[t[2]];
    const Vec3 a = b0 * n0 + b1 * n1 + b2 * n2;  // as in point_into, so n below is h.n up to flip_
    const double len = glm::length(a);
    if (len > 0) {
      const Vec3 n = a / len;
      // d(a/|a|) = (I - n n^T) da / |a| with da/du = n1 - n0, da/dv = n2 - n0.
      const Vec3 dau = n1 - n0, dav = n2 - n0;
      h.dndu = (dau - glm::dot(n, dau) * n) / len;
      h.dndv = (dav - glm::dot(n, dav) * n) / len;
    }
  }
  if (flip_) {
    h.dndu = -h.dndu;
    h.dndv = -h.dndv;
  }
}

namespace {

// The arithmetic of TriangleMesh::refine_uv, cloned for CPUs with FMA: without -mfma each
// std::fma of difference_of_products is a call into libm, and every call spills the live xmm
// registers (all caller-saved). fma is correctly rounded either way, and contraction of
// a * b + c into fma is switched off for this function (GCC contracts by default once FMA is
// available), so both clones give the same bits as the out-of-line calls did.
[[gnu::target_clones("fma", "default"), gnu::optimize("fp-contract=off")]] Vec2 refine_uv_impl(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                                             const Vec3& nrm, double d00, double d01, double d11,
                                                             double denom, const Ray& ray, double t_float,
                                                             const Vec2& uv_float, double* t_out) {
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const double den = glm::dot(nrm, ray.d);
  double t = t_float;
  Vec2 uv = uv_float;
  if (den != 0) {
    t = glm::dot(nrm, p0 - ray.o) / den;
    const Vec3 w = ray.at(t) - p0;
    const double d20 = glm::dot(w, e1), d21 = glm::dot(w, e2);
    if (denom > 0) {
      double b1 = difference_of_products(d11, d20, d01, d21) / denom;
      double b2 = difference_of_products(d00, d21, d01, d20) / denom;
      b1 = std::max(b1, 0.0);
      b2 = std::max(b2, 0.0);
      const double s = b1 + b2;
      if (s > 1) {
        b1 /= s;
        b2 /= s;
      }
      uv = {b1, b2};
    }
  }
  *t_out = t;
  return uv;
}

}  // namespace

Vec2 TriangleMesh::refine_uv(uint32_t prim, const Ray& ray, double t_float, const Vec2& uv_float, double* t_out) const {
  const glm::uvec3 tri = tris_[prim];
  const TriangleFrame& f = frames_[prim];
  return refine_uv_impl(pos_[tri[0]], pos_[tri[1]], pos_[tri[2]], f.plane, f.d00, f.d01, f.d11, f.denom, ray, t_float,
                        uv_float, t_out);
}

void TriangleMesh::refine_hit(uint32_t prim, const Ray& ray, double t_float, const Vec2& uv_float, Hit* h) const {
  double t = 0.0;
  const Vec2 uv = refine_uv(prim, ray, t_float, uv_float, &t);
  surface_at(prim, uv, h);
  h->t = t;
}


Vec2 TriangleMesh::texcoord(uint32_t prim, const Vec2& uv) const {
  if (uv_.empty()) return uv;
  const glm::uvec3 t = tris_[prim];
  return (1 - uv.x - uv.y) * uv_[t[0]] + uv.x * uv_[t[1]] + uv.y * uv_[t[2]];
}

AreaSample TriangleMesh::sample_area(const Vec2& u) const {
  AreaSample a;
  a.pdf_area = sample_area(u, &a.hit);
  return a;
}

double TriangleMesh::sample_area(const Vec2& u, Hit* h) const {
  Vec2 uv;
  const uint32_t prim = sample_uv(u, &uv);
  surface_at(prim, uv, h);
  return 1.0 / total_area_;
}

SurfacePoint TriangleMesh::sample_point(const Vec2& u, double* pdf_area) const {
  Vec2 uv;
  const uint32_t prim = sample_uv(u, &uv);
  *pdf_area = 1.0 / total_area_;
  SurfacePoint p;
  point_into(prim, uv, 0.0, &p);
  return p;
}

}  // namespace tb

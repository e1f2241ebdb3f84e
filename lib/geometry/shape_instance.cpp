#include "lib/geometry/shape_instance.h"

#include <algorithm>
#include <stdexcept>

#include "lib/geometry/spawn.h"
#include "lib/geometry/weingarten.h"

namespace tb {

ShapeInstance::ShapeInstance(std::shared_ptr<const AnalyticShape> shape, const AffineTransform& to_world,
                             bool flip_normal)
    : shape_(std::move(shape)), xf_(to_world), flip_(flip_normal) {
  if (!shape_) throw std::invalid_argument("ShapeInstance: null shape");
  if (!(std::abs(xf_.determinant()) > 0)) throw std::invalid_argument("ShapeInstance: singular transform");
}

Vec3 ShapeInstance::object_normal(const SurfaceDerivatives& s) const {
  Vec3 c = glm::cross(s.pu, s.pv);
  const double len = glm::length(c);
  if (len > 1e-14 * glm::length(s.pu + s.pv) * glm::length(s.pu + s.pv)) return c / len;
  // Singular points of the parameterisation (poles, apex, disk centre): the normal is the limit
  // along v, from the cross product of the mixed derivative with pv (pu vanishes linearly).
  c = glm::cross(s.puv, s.pv);
  const double l2 = glm::length(c);
  return l2 > 0 ? c / l2 : Vec3(0, 0, 1);
}

Hit ShapeInstance::surface_at(const Vec2& uv) const {
  const SurfaceDerivatives so = shape_->derivatives(uv);
  SurfaceDerivatives sw;
  sw.p = xf_.point(so.p);
  sw.pu = xf_.vector(so.pu);
  sw.pv = xf_.vector(so.pv);
  sw.puu = xf_.vector(so.puu);
  sw.puv = xf_.vector(so.puv);
  sw.pvv = xf_.vector(so.pvv);
  Hit h;
  h.p = sw.p;
  h.uv = uv;
  h.dpdu = sw.pu;
  h.dpdv = sw.pv;
  Vec3 n = glm::normalize(glm::transpose(xf_.inverse_linear()) * object_normal(so));
  if (flip_) n = -n;
  h.n = h.ng = n;
  weingarten(sw, n, &h.dndu, &h.dndv);
  // Isotropic in object space: the intersectors combine all coordinates (a disk hit at z = 0
  // still has an uncertain z as seen by the ray-plane test).
  const Vec3 ap = glm::abs(so.p);
  const Vec3 e_obj = Vec3((shape_->error_factor() * std::max({ap.x, ap.y, ap.z}) + shape_->error_scale()) * kEpsilon);
  h.p_error = xf_.point_error(so.p, e_obj) + xf_.round_trip_error(sw.p);
  return h;
}

std::optional<Hit> ShapeInstance::intersect(const Ray& ray, double tmin, double tmax) const {
  const Vec3 o = xf_.inverse_point(ray.o), d = xf_.inverse_vector(ray.d);
  const std::optional<double> t = shape_->intersect(o, d, tmin, tmax);
  if (!t) return std::nullopt;
  Hit h = surface_at(shape_->project(o + *t * d));
  h.t = *t;
  return h;
}

bool ShapeInstance::intersects(const Ray& ray, double tmin, double tmax) const {
  return shape_->intersect(xf_.inverse_point(ray.o), xf_.inverse_vector(ray.d), tmin, tmax).has_value();
}

Bounds3 ShapeInstance::world_bounds() const {
  const Bounds3 ob = shape_->bounds();
  Bounds3 wb;
  for (int i = 0; i < 8; ++i) wb.extend(xf_.point(ob.corner(i)));
  // Inflate so that float rays (slightly different from the double ray the intersector uses)
  // still reach the primitive: relative 1e-5 of the extent plus float rounding of the corners.
  const Vec3 pad = 1e-5 * Vec3(glm::length(wb.diagonal())) + 1e-6 * glm::max(glm::abs(wb.lo), glm::abs(wb.hi));
  wb.lo -= pad;
  wb.hi += pad;
  return wb;
}

double ShapeInstance::pdf_area(const Vec2& uv) const {
  // World area element = |det M| |M^-T n| times the object one (Nanson's formula); valid at
  // singular points of the parameterisation too.
  const Vec3 n = object_normal(shape_->derivatives(uv));
  return shape_->pdf_area(uv) / (std::abs(xf_.determinant()) * glm::length(glm::transpose(xf_.inverse_linear()) * n));
}

AreaSample ShapeInstance::sample_area(const Vec2& u) const {
  const Vec2 uv = shape_->sample_uv(u);
  return {surface_at(uv), pdf_area(uv)};
}

}  // namespace tb

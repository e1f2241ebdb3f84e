#include "lib/geometry/cylinder.h"

#include <stdexcept>
#include <utility>

namespace tb {

Cylinder::Cylinder(double radius, double z0, double z1) : r_(radius), z0_(z0), z1_(z1) {
  if (!(radius > 0) || !(z1 > z0)) throw std::invalid_argument("Cylinder: need radius > 0 and z1 > z0");
}

SurfaceDerivatives Cylinder::derivatives(const Vec2& uv) const {
  const double phi = 2 * kPi * uv.x, c = std::cos(phi), s = std::sin(phi), a = 2 * kPi;
  SurfaceDerivatives d;
  d.p = {r_ * c, r_ * s, z0_ + (z1_ - z0_) * uv.y};
  d.pu = (a * r_) * Vec3(-s, c, 0);
  d.pv = {0, 0, z1_ - z0_};
  d.puu = (-a * a * r_) * Vec3(c, s, 0);
  return d;
}

Vec2 Cylinder::project(const Vec3& p) const {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  return {phi * kInv2Pi, std::clamp((p.z - z0_) / (z1_ - z0_), 0.0, 1.0)};
}

std::optional<double> Cylinder::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const {
  // (ox + t dx)^2 + (oy + t dy)^2 = r^2 with the line-distance discriminant (as for the sphere).
  const double a = d.x * d.x + d.y * d.y;
  if (a == 0) return std::nullopt;
  const double b = 2 * (o.x * d.x + o.y * d.y);
  const double c = o.x * o.x + o.y * o.y - r_ * r_;
  const double f = b / (2 * a);
  const double len = std::hypot(o.x - f * d.x, o.y - f * d.y);
  const double disc = 4 * a * (r_ + len) * (r_ - len);
  if (disc < 0) return std::nullopt;
  const double root = std::sqrt(disc);
  const double q = b < 0 ? -0.5 * (b - root) : -0.5 * (b + root);
  double t0 = q / a, t1 = q != 0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  for (double t : {t0, t1}) {
    if (!(t > tmin && t < tmax)) continue;
    const double z = o.z + t * d.z;
    if (z >= z0_ && z <= z1_) return t;
  }
  return std::nullopt;
}

}  // namespace tb

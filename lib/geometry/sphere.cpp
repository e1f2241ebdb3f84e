#include "lib/geometry/sphere.h"

#include <stdexcept>

#include "lib/geometry/quadratic.h"

namespace tb {

Sphere::Sphere(double radius) : r_(radius) {
  if (!(radius > 0)) throw std::invalid_argument("Sphere: radius must be positive");
}

SurfaceDerivatives Sphere::derivatives(const Vec2& uv) const {
  const double phi = 2 * kPi * uv.x, theta = kPi * uv.y;
  const double cp = std::cos(phi), sp = std::sin(phi), ct = std::cos(theta), st = std::sin(theta);
  const double a = 2 * kPi, b = kPi;
  SurfaceDerivatives s;
  s.p = r_ * Vec3(st * cp, st * sp, -ct);
  s.pu = (a * r_) * Vec3(-st * sp, st * cp, 0);
  s.pv = (b * r_) * Vec3(ct * cp, ct * sp, st);
  s.puu = (-a * a * r_) * Vec3(st * cp, st * sp, 0);
  s.puv = (a * b * r_) * Vec3(-ct * sp, ct * cp, 0);
  s.pvv = (b * b * r_) * Vec3(-st * cp, -st * sp, ct);
  return s;
}

Vec2 Sphere::project(const Vec3& p) const {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  const double theta = std::atan2(std::hypot(p.x, p.y), -p.z);
  return {phi * kInv2Pi, theta * kInvPi};
}

std::optional<double> Sphere::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const {
  // |o + t d|^2 = r^2; the discriminant from the distance of the line to the centre
  // (pbrt-v4 Sec. 6.8.3) avoids the cancellation in b^2 - 4ac.
  const double a = glm::dot(d, d);
  const double b = 2 * glm::dot(o, d);
  const double c = glm::dot(o, o) - r_ * r_;
  const Vec3 v = o - (b / (2 * a)) * d;
  const double len = glm::length(v);
  const double disc = 4 * a * (r_ + len) * (r_ - len);
  if (disc < 0) return std::nullopt;
  const double root = std::sqrt(disc);
  const double q = b < 0 ? -0.5 * (b - root) : -0.5 * (b + root);
  double t0 = q / a, t1 = q != 0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 > tmin && t0 < tmax) return t0;
  if (t1 > tmin && t1 < tmax) return t1;
  return std::nullopt;
}

Bounds3 Sphere::bounds() const { return {Vec3(-r_), Vec3(r_)}; }

Vec2 Sphere::sample_uv(const Vec2& u) const {
  const double theta = 2 * std::asin(std::sqrt(u.x));
  return {u.y, theta * kInvPi};
}

}  // namespace tb

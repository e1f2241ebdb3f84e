#include "lib/geometry/paraboloid.h"

#include <stdexcept>
#include <utility>

namespace tb {

Paraboloid::Paraboloid(double radius, double height) : R_(radius), h_(height) {
  if (!(radius > 0) || !(height > 0)) throw std::invalid_argument("Paraboloid: radius and height must be positive");
  c_ = 4 * h_ * h_ / (R_ * R_ * R_ * R_);
  a_ = std::expm1(1.5 * std::log1p(c_ * R_ * R_));
}

double Paraboloid::area() const { return 2 * kPi * a_ / (3 * c_); }

SurfaceDerivatives Paraboloid::derivatives(const Vec2& uv) const {
  const double phi = 2 * kPi * uv.x, c = std::cos(phi), s = std::sin(phi), a = 2 * kPi, v = uv.y;
  SurfaceDerivatives d;
  d.p = {R_ * v * c, R_ * v * s, h_ * v * v};
  d.pu = (a * R_ * v) * Vec3(-s, c, 0);
  d.pv = {R_ * c, R_ * s, 2 * h_ * v};
  d.puu = (-a * a * R_ * v) * Vec3(c, s, 0);
  d.puv = (a * R_) * Vec3(-s, c, 0);
  d.pvv = {0, 0, 2 * h_};
  return d;
}

Vec2 Paraboloid::project(const Vec3& p) const {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  return {phi * kInv2Pi, std::clamp(std::hypot(p.x, p.y) / R_, 0.0, 1.0)};
}

std::optional<double> Paraboloid::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const {
  // h ((ox + t dx)^2 + (oy + t dy)^2) - R^2 (oz + t dz) = 0.
  const double A = h_ * (d.x * d.x + d.y * d.y);
  const double B = 2 * h_ * (o.x * d.x + o.y * d.y) - R_ * R_ * d.z;
  const double C = h_ * (o.x * o.x + o.y * o.y) - R_ * R_ * o.z;
  double t0, t1;
  if (A == 0) {
    if (B == 0) return std::nullopt;
    t0 = t1 = -C / B;
  } else {
    const double disc = B * B - 4 * A * C;
    if (disc < 0) return std::nullopt;
    const double root = std::sqrt(disc);
    const double q = B < 0 ? -0.5 * (B - root) : -0.5 * (B + root);
    t0 = q / A;
    t1 = q != 0 ? C / q : t0;
    if (t0 > t1) std::swap(t0, t1);
  }
  for (double t : {t0, t1}) {
    if (!(t > tmin && t < tmax)) continue;
    const double z = o.z + t * d.z;
    if (z >= 0 && z <= h_) return t;
  }
  return std::nullopt;
}

Vec2 Paraboloid::sample_uv(const Vec2& u) const {
  const double rho2 = std::expm1((2.0 / 3.0) * std::log1p(u.x * a_)) / c_;
  return {u.y, std::clamp(std::sqrt(rho2) / R_, 0.0, 1.0)};
}

}  // namespace tb

#include "lib/geometry/disk.h"

#include <stdexcept>

namespace tb {

Disk::Disk(double radius, double inner_radius) : ro_(radius), ri_(inner_radius) {
  if (!(radius > 0) || !(inner_radius >= 0) || !(inner_radius < radius))
    throw std::invalid_argument("Disk: need 0 <= inner_radius < radius");
}

SurfaceDerivatives Disk::derivatives(const Vec2& uv) const {
  const double phi = 2 * kPi * uv.x, w = ro_ - ri_, rho = ro_ - w * uv.y;
  const double c = std::cos(phi), s = std::sin(phi), a = 2 * kPi;
  SurfaceDerivatives d;
  d.p = {rho * c, rho * s, 0};
  d.pu = (a * rho) * Vec3(-s, c, 0);
  d.pv = -w * Vec3(c, s, 0);
  d.puu = (-a * a * rho) * Vec3(c, s, 0);
  d.puv = (-a * w) * Vec3(-s, c, 0);
  d.pvv = Vec3(0.0);
  return d;
}

Vec2 Disk::project(const Vec3& p) const {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  const double rho = std::hypot(p.x, p.y);
  return {phi * kInv2Pi, std::clamp((ro_ - rho) / (ro_ - ri_), 0.0, 1.0)};
}

std::optional<double> Disk::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const {
  if (d.z == 0) return std::nullopt;
  const double t = -o.z / d.z;
  if (!(t > tmin && t < tmax)) return std::nullopt;
  const double x = o.x + t * d.x, y = o.y + t * d.y;
  const double rho2 = x * x + y * y;
  if (rho2 > ro_ * ro_ || rho2 < ri_ * ri_) return std::nullopt;
  return t;
}

Bounds3 Disk::bounds() const { return {Vec3(-ro_, -ro_, 0), Vec3(ro_, ro_, 0)}; }

Vec2 Disk::sample_uv(const Vec2& u) const {
  const double rho = std::sqrt(ri_ * ri_ + u.x * (ro_ - ri_) * (ro_ + ri_));
  return {u.y, std::clamp((ro_ - rho) / (ro_ - ri_), 0.0, 1.0)};
}

}  // namespace tb

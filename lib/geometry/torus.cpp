#include "lib/geometry/torus.h"

#include <array>
#include <stdexcept>

#include "lib/geometry/polynomial_roots.h"
#include "lib/geometry/quadratic.h"

namespace tb {

Torus::Torus(double major_radius, double minor_radius) : R_(major_radius), r_(minor_radius) {
  if (!(minor_radius > 0) || !(major_radius > minor_radius))
    throw std::invalid_argument("Torus: need 0 < minor_radius < major_radius");
}

SurfaceDerivatives Torus::derivatives(const Vec2& uv) const {
  const double phi = 2 * kPi * uv.x, theta = 2 * kPi * uv.y, a = 2 * kPi;
  const double cp = std::cos(phi), sp = std::sin(phi), ct = std::cos(theta), st = std::sin(theta);
  const double w = R_ + r_ * ct;
  SurfaceDerivatives d;
  d.p = {w * cp, w * sp, r_ * st};
  d.pu = (a * w) * Vec3(-sp, cp, 0);
  d.pv = (a * r_) * Vec3(-st * cp, -st * sp, ct);
  d.puu = (-a * a * w) * Vec3(cp, sp, 0);
  d.puv = (a * a * r_ * st) * Vec3(sp, -cp, 0);
  d.pvv = (-a * a * r_) * Vec3(ct * cp, ct * sp, st);
  return d;
}

Vec2 Torus::project(const Vec3& p) const {
  double phi = std::atan2(p.y, p.x);
  if (phi < 0) phi += 2 * kPi;
  double theta = std::atan2(p.z, std::hypot(p.x, p.y) - R_);
  if (theta < 0) theta += 2 * kPi;
  return {phi * kInv2Pi, theta * kInv2Pi};
}

std::optional<double> Torus::intersect(const Vec3& o_in, const Vec3& d, double tmin, double tmax) const {
  // Restrict to the bounding sphere (radius R + r, slightly inflated).
  const double rb = (R_ + r_) * (1 + 1e-9);
  double s0, s1;
  const double dd = glm::dot(d, d);
  if (!solve_quadratic(dd, 2 * glm::dot(o_in, d), glm::dot(o_in, o_in) - rb * rb, &s0, &s1)) return std::nullopt;
  double lo = std::max(tmin, s0), hi = std::min(tmax, s1);
  if (!(lo < hi)) return std::nullopt;
  // A far origin is moved to the bounding-sphere entry to keep the coefficients well scaled;
  // an origin inside the sphere (spawned rays) is used as is.
  const double shift = s0 > 0 ? s0 : 0.0;
  const Vec3 o = o_in + shift * d;
  lo -= shift;
  hi -= shift;
  const double rho = std::hypot(o.x, o.y);
  const double R2 = R_ * R_, r2 = r_ * r_;
  const double k = glm::dot(o, o) + R2 - r2;
  const double b1 = glm::dot(o, d);
  const double dxy = d.x * d.x + d.y * d.y;
  std::array<double, 5> c;
  c[4] = dd * dd;
  c[3] = 4 * dd * b1;
  c[2] = 4 * b1 * b1 + 2 * dd * k - 4 * R2 * dxy;
  c[1] = 4 * b1 * k - 8 * R2 * (o.x * d.x + o.y * d.y);
  c[0] = (sqr(rho - R_) + o.z * o.z - r2) * (sqr(rho + R_) + o.z * o.z - r2);
  const double t = first_polynomial_root(c, lo, hi);
  if (std::isnan(t)) return std::nullopt;
  return t + shift;
}

Bounds3 Torus::bounds() const { return {Vec3(-(R_ + r_), -(R_ + r_), -r_), Vec3(R_ + r_, R_ + r_, r_)}; }

Vec2 Torus::sample_uv(const Vec2& u) const {
  // Solve F(theta) = R theta + r sin theta - 2 pi R u = 0 on [0, 2 pi]; F is increasing.
  const double target = 2 * kPi * R_ * u.x;
  double lo = 0, hi = 2 * kPi, theta = 2 * kPi * u.x;
  for (int it = 0; it < 100; ++it) {
    const double f = R_ * theta + r_ * std::sin(theta) - target;
    if (f == 0) break;
    if (f < 0) lo = theta; else hi = theta;
    const double df = R_ + r_ * std::cos(theta);
    double next = theta - f / df;
    if (!(next >= lo && next <= hi)) next = 0.5 * (lo + hi);
    if (next == theta) break;
    theta = next;
  }
  return {u.y, std::clamp(theta * kInv2Pi, 0.0, 1.0)};
}

}  // namespace tb

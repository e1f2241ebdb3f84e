// Torus about the z axis, major radius R (tube centre), minor radius r < R:
// phi = 2 pi u, theta = 2 pi v,
// p = ((R + r cos theta) cos phi, (R + r cos theta) sin phi, r sin theta); normal outward.
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Torus final : public AnalyticShape {
 public:
  Torus(double major_radius, double minor_radius);
  std::string name() const override { return "torus"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  // The quartic f(o + t d) = 0 with f(p) = (|p|^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2), solved by
  // root isolation in double (polynomial_roots.h) on the part of the ray inside the bounding
  // sphere; f(o) is evaluated in the factored form ((rho - R)^2 + z^2 - r^2)((rho + R)^2 + z^2 - r^2)
  // so that the root near a spawned origin carries no cancellation error.
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override;
  bool closed() const override { return true; }
  double area() const override { return 4 * kPi * kPi * R_ * r_; }
  // Exactly uniform by area: phi uniform; theta has density (R + r cos theta) / (2 pi R), whose
  // CDF (R theta + r sin theta) / (2 pi R) is inverted by safeguarded Newton iteration to double
  // precision.
  Vec2 sample_uv(const Vec2& u) const override;
  double error_scale() const override { return 64.0 * r_; }

 private:
  double R_, r_;
};

}  // namespace tb

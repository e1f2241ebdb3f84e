// Annulus / disk in the plane z = 0, inner radius ri >= 0, outer radius ro:
// phi = 2 pi u, rho = ro - (ro - ri) v, p = (rho cos phi, rho sin phi, 0); normal +z.
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Disk final : public AnalyticShape {
 public:
  explicit Disk(double radius, double inner_radius = 0.0);
  std::string name() const override { return "disk"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override;
  bool closed() const override { return false; }
  double area() const override { return kPi * (ro_ * ro_ - ri_ * ri_); }
  // Uniform by area: rho^2 uniform in [ri^2, ro^2].
  Vec2 sample_uv(const Vec2& u) const override;

 private:
  double ro_, ri_;
};

}  // namespace tb

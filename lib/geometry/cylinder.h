// Open cylinder of radius r about the z axis, z in [z0, z1]:
// phi = 2 pi u, p = (r cos phi, r sin phi, z0 + (z1 - z0) v); normal away from the axis.
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Cylinder final : public AnalyticShape {
 public:
  Cylinder(double radius, double z0, double z1);
  std::string name() const override { return "cylinder"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override { return {Vec3(-r_, -r_, z0_), Vec3(r_, r_, z1_)}; }
  bool closed() const override { return false; }
  double area() const override { return 2 * kPi * r_ * (z1_ - z0_); }
  Vec2 sample_uv(const Vec2& u) const override { return u; }  // the map has constant |pu x pv|

 private:
  double r_, z0_, z1_;
};

}  // namespace tb

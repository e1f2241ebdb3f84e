// Paraboloid z = h (rho / R)^2 for rho <= R (a bowl opening towards +z, open at z = h):
// phi = 2 pi u, rho = R v, p = (R v cos phi, R v sin phi, h v^2). The normal points away from
// the axis and down (the outside of the bowl).
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Paraboloid final : public AnalyticShape {
 public:
  Paraboloid(double radius, double height);
  std::string name() const override { return "paraboloid"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override { return {Vec3(-R_, -R_, 0), Vec3(R_, R_, h_)}; }
  bool closed() const override { return false; }
  // Surface of revolution: dA = rho sqrt(1 + c rho^2) drho dphi with c = 4 h^2 / R^4, so
  // A = 2 pi ((1 + c R^2)^(3/2) - 1) / (3 c).
  double area() const override;
  // Exactly uniform by area: the rho-CDF ((1 + c rho^2)^(3/2) - 1) / ((1 + c R^2)^(3/2) - 1) is
  // inverted in closed form (with expm1/log1p so that flat paraboloids keep their precision).
  Vec2 sample_uv(const Vec2& u) const override;

 private:
  double R_, h_, c_, a_;  // a_ = (1 + c R^2)^(3/2) - 1
};

}  // namespace tb

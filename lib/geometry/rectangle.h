// Rectangle [-a, a] x [-b, b] in the plane z = 0: p = (a (2u - 1), b (2v - 1), 0); normal +z.
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Rectangle final : public AnalyticShape {
 public:
  Rectangle(double half_x, double half_y);
  std::string name() const override { return "rectangle"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override { return {Vec3(-a_, -b_, 0), Vec3(a_, b_, 0)}; }
  bool closed() const override { return false; }
  double area() const override { return 4 * a_ * b_; }
  Vec2 sample_uv(const Vec2& u) const override { return u; }  // uniform: the map is affine

 private:
  double a_, b_;
};

}  // namespace tb

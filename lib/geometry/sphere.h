// Sphere of radius r about the origin: phi = 2 pi u, theta = pi v,
// p = r (sin theta cos phi, sin theta sin phi, -cos theta) (v = 0 is the south pole).
#pragma once

#include "lib/geometry/analytic_shape.h"

namespace tb {

class Sphere final : public AnalyticShape {
 public:
  explicit Sphere(double radius);
  std::string name() const override { return "sphere"; }
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec2 project(const Vec3& p) const override;
  std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const override;
  Bounds3 bounds() const override;
  bool closed() const override { return true; }
  double area() const override { return 4 * kPi * r_ * r_; }
  // Uniform by area: cos theta uniform (Archimedes), written with theta = 2 asin(sqrt(u)) to keep
  // precision at the poles.
  Vec2 sample_uv(const Vec2& u) const override;
  double radius() const { return r_; }

 private:
  double r_;
};

}  // namespace tb

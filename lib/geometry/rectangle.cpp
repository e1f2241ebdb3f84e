#include "lib/geometry/rectangle.h"

#include <stdexcept>

namespace tb {

Rectangle::Rectangle(double half_x, double half_y) : a_(half_x), b_(half_y) {
  if (!(half_x > 0) || !(half_y > 0)) throw std::invalid_argument("Rectangle: half extents must be positive");
}

SurfaceDerivatives Rectangle::derivatives(const Vec2& uv) const {
  SurfaceDerivatives d;
  d.p = {a_ * (2 * uv.x - 1), b_ * (2 * uv.y - 1), 0};
  d.pu = {2 * a_, 0, 0};
  d.pv = {0, 2 * b_, 0};
  return d;
}

Vec2 Rectangle::project(const Vec3& p) const {
  return {std::clamp(0.5 * (p.x / a_ + 1), 0.0, 1.0), std::clamp(0.5 * (p.y / b_ + 1), 0.0, 1.0)};
}

std::optional<double> Rectangle::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const {
  if (d.z == 0) return std::nullopt;
  const double t = -o.z / d.z;
  if (!(t > tmin && t < tmax)) return std::nullopt;
  const double x = o.x + t * d.x, y = o.y + t * d.y;
  if (std::abs(x) > a_ || std::abs(y) > b_) return std::nullopt;
  return t;
}

}  // namespace tb

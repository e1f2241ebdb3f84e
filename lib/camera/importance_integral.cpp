#include "lib/camera/importance_integral.h"

#include <algorithm>
#include <vector>

#include <boost/math/quadrature/gauss_kronrod.hpp>

namespace tb {

double integrate_importance_cos(const Camera& camera, const std::function<double(const Ray&)>& importance,
                                const Vec2& p, double h, double tolerance) {
  using GK = boost::math::quadrature::gauss_kronrod<double, 31>;
  const PerspectiveProjection& proj = camera.projection();
  const double x0 = -h * proj.tan_half_x(), x1 = h * proj.tan_half_x();
  const double y0 = -h * proj.tan_half_y(), y1 = h * proj.tan_half_y();
  const Vec3 origin = proj.to_world_point(Vec3(p.x, p.y, 0.0));
  // Distance from p to the rectangle edge along (cos phi, sin phi); p is inside the rectangle.
  const auto exit_distance = [&](double phi) {
    const double c = std::cos(phi), s = std::sin(phi);
    double t = kInfinity;
    if (c > 0) t = std::min(t, (x1 - p.x) / c);
    if (c < 0) t = std::min(t, (x0 - p.x) / c);
    if (s > 0) t = std::min(t, (y1 - p.y) / s);
    if (s < 0) t = std::min(t, (y0 - p.y) / s);
    return t;
  };
  const auto inner = [&](double phi) {
    const double theta_max = std::atan(exit_distance(phi) / h);
    const double c = std::cos(phi), s = std::sin(phi);
    return GK::integrate(
        [&](double theta) {
          const double st = std::sin(theta), ct = std::cos(theta);
          const Ray ray{origin, proj.to_world_dir(Vec3(st * c, st * s, ct))};
          return importance(ray) * ct * st;
        },
        0.0, theta_max, 10, tolerance);
  };
  // Split azimuth at the four corners (kinks of theta_max(phi)).
  std::vector<double> cuts = {0.0, 2 * kPi};
  for (double cx : {x0, x1})
    for (double cy : {y0, y1}) {
      double a = std::atan2(cy - p.y, cx - p.x);
      if (a < 0) a += 2 * kPi;
      cuts.push_back(a);
    }
  std::sort(cuts.begin(), cuts.end());
  double total = 0.0;
  for (size_t i = 0; i + 1 < cuts.size(); ++i)
    if (cuts[i + 1] > cuts[i]) total += GK::integrate(inner, cuts[i], cuts[i + 1], 10, tolerance);
  return total;
}

}  // namespace tb

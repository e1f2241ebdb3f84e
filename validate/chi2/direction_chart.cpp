#include "validate/chi2/direction_chart.h"

namespace tb {

namespace {
// The q-quantile of v (0 <= q <= 1), by partial sort; v is reordered.
double quantile(std::vector<double>& v, double q) {
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
}  // namespace

std::optional<Chi2DirectionChart> Chi2DirectionChart::fit(const std::vector<Vec3>& pilot, const Vec3& guess,
                                                          double coverage, int n) {
  const Frame f0 = Frame::from_z(glm::normalize(guess));
  std::vector<double> xs, ys;
  for (const Vec3& w : pilot) {
    const Vec3 l = f0.to_local(w);
    if (!(l.z > 0.0)) continue;
    xs.push_back(l.x);
    ys.push_back(l.y);
  }
  if (xs.size() < 16) return std::nullopt;
  std::vector<double> tx = xs, ty = ys;
  const Vec2 c(quantile(tx, 0.5), quantile(ty, 0.5));
  // The centre direction on the sphere, then the spread about it in its own chart.
  const Chi2DirectionChart centred = around(f0.to_world(Vec3(c.x, c.y, z_of(c))), 0.7, n);
  std::vector<double> radius;
  radius.reserve(pilot.size());
  for (const Vec3& w : pilot) {
    const Vec3 l = centred.frame.to_local(w);
    radius.push_back(l.z > 0.0 ? std::max(std::abs(l.x), std::abs(l.y)) : 1.0);
  }
  const double h = quantile(radius, coverage);
  if (!(h > 0.0)) return std::nullopt;
  return around(centred.frame.n, h, n);
}

}  // namespace tb

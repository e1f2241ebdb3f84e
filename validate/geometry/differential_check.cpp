#include "validate/geometry/differential_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tb {
namespace {

// Central differences of (p, n) along parameter `axis` with step factor `scale`.
std::array<Vec3, 2> central(const std::function<Hit(const Vec2&)>& surface, const Vec2& uv, int axis, double scale) {
  const double h0 = scale * std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(uv[axis]));
  Vec2 up = uv, um = uv;
  up[axis] += h0;
  um[axis] -= h0;
  const double h = up[axis] - um[axis];  // the step actually taken
  const Hit a = surface(up), b = surface(um);
  return {(a.p - b.p) / h, (a.n - b.n) / h};
}

double rel(const Vec3& analytic, const Vec3& fd) {
  return glm::length(analytic - fd) / std::max(1.0, glm::length(fd));
}

}  // namespace

DifferentialError check_differentials_at(const std::function<Hit(const Vec2&)>& surface, const Vec2& uv) {
  const Hit h = surface(uv);
  DifferentialError e;
  for (int axis = 0; axis < 2; ++axis) {
    const auto d1 = central(surface, uv, axis, 1.0), d2 = central(surface, uv, axis, 0.5);
    const Vec3& dp = axis == 0 ? h.dpdu : h.dpdv;
    const Vec3& dn = axis == 0 ? h.dndu : h.dndv;
    e.step_disagreement = std::max({e.step_disagreement, rel(d1[0], d2[0]), rel(d1[1], d2[1])});
    e.rel_error = std::max({e.rel_error, rel(dp, d1[0]), rel(dn, d1[1])});
  }
  // Truncation differs by ~3/4 of the O(h^2) term between h and h/2; far above that, a kink.
  e.skipped = e.step_disagreement > 1e-4;
  return e;
}

}  // namespace tb

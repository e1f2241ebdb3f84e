#include "lib/light/light.h"

#include "lib/core/warp_sphere.h"

namespace tb {

std::optional<LightLiPoint> Light::sample_li_point(const Vec3& ref, const Vec2& u) const {
  const std::optional<LightLiSample> s = sample_li(ref, u);
  if (!s) return std::nullopt;
  return static_cast<const LightLiPoint&>(*s);
}

Vec3 sample_emission_direction(const Vec3& n, bool two_sided, const Vec2& u) {
  Vec2 uu = u;
  double side = 1.0;
  if (two_sided) {
    // Reuse the first uniform: [0, 1/2) front, [1/2, 1) back, rescaled to [0, 1).
    side = uu.x < 0.5 ? 1.0 : -1.0;
    uu.x = uu.x < 0.5 ? 2.0 * uu.x : std::min(2.0 * uu.x - 1.0, kOneMinusEpsilon);
  }
  const Frame f = Frame::from_z(side * n);
  return f.to_world(sample_cosine_hemisphere(uu));
}

double pdf_emission_direction(const Vec3& n, bool two_sided, const Vec3& w) {
  const double c = glm::dot(n, w) / glm::length(w);
  if (two_sided) return 0.5 * std::abs(c) * kInvPi;
  return c > 0 ? c * kInvPi : 0.0;
}

}  // namespace tb

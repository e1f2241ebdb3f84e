#include "lib/material/lambert.h"

namespace tb {
namespace {

// Shirley & Chiu 1997 concentric map of [0,1)^2 to the unit disk, lifted to the hemisphere
// (Malley's method): density |cos theta| / pi in solid angle.
Vec3 cosine_hemisphere(const Vec2& u) {
  const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
  double r = 0.0, phi = 0.0;
  if (a != 0.0 || b != 0.0) {
    if (std::abs(a) > std::abs(b)) {
      r = a;
      phi = kPiOver4 * (b / a);
    } else {
      r = b;
      phi = kPiOver2 - kPiOver4 * (a / b);
    }
  }
  const double x = r * std::cos(phi), y = r * std::sin(phi);
  return {x, y, safe_sqrt(1.0 - x * x - y * y)};
}

}  // namespace

Rgb LambertBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (wo.z * wi.z <= 0) return Rgb(0.0);
  return r_ * kInvPi;
}

std::optional<BsdfSample> LambertBsdf::sample(const Vec3& wo, double, const Vec2& u, TransportMode) const {
  if (wo.z == 0) return std::nullopt;
  Vec3 wi = cosine_hemisphere(u);
  if (wi.z == 0) return std::nullopt;  // measure-zero rim of the disk
  if (wo.z < 0) wi.z = -wi.z;
  BsdfSample s;
  s.wi = wi;
  s.f = r_ * kInvPi;
  s.pdf = std::abs(wi.z) * kInvPi;
  s.weight = r_;  // f |cos| / pdf = R exactly
  s.flags = bsdf_flags::kReflection | bsdf_flags::kDiffuse;
  return s;
}

double LambertBsdf::pdf(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (wo.z * wi.z <= 0) return 0.0;
  return std::abs(wi.z) * kInvPi;
}

}  // namespace tb

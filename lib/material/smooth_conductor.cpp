#include "lib/material/smooth_conductor.h"

#include "lib/material/fresnel.h"

namespace tb {

std::optional<BsdfSample> SmoothConductorBsdf::sample(const Vec3& wo, double, const Vec2&, TransportMode) const {
  if (wo.z == 0) return std::nullopt;
  BsdfSample s;
  s.wi = Vec3(-wo.x, -wo.y, wo.z);
  const Rgb F = fresnel_conductor(wo.z, eta_, k_);
  s.f = F / std::abs(wo.z);
  s.pdf = 1.0;
  s.weight = F;
  s.flags = bsdf_flags::kReflection | bsdf_flags::kDelta;
  return s;
}

}  // namespace tb

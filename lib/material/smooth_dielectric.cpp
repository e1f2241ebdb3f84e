#include "lib/material/smooth_dielectric.h"

#include <stdexcept>

#include "lib/material/fresnel.h"

namespace tb {

SmoothDielectricBsdf::SmoothDielectricBsdf(double eta) : eta_(eta) {
  if (!(eta > 0) || !std::isfinite(eta)) throw std::invalid_argument("smooth_dielectric: eta must be > 0");
}

std::optional<BsdfSample> SmoothDielectricBsdf::sample(const Vec3& wo, double uc, const Vec2&,
                                                       TransportMode mode) const {
  if (wo.z == 0) return std::nullopt;
  const bool outside = wo.z > 0;
  const double eta_rel = outside ? eta_ : 1.0 / eta_;  // eta_other_side / eta_wo_side
  const double F = fresnel_dielectric(wo.z, eta_rel);
  BsdfSample s;
  if (uc < F) {
    s.wi = Vec3(-wo.x, -wo.y, wo.z);
    s.f = Rgb(F / std::abs(wo.z));
    s.pdf = F;
    s.weight = Rgb(1.0);
    s.flags = bsdf_flags::kReflection | bsdf_flags::kDelta;
    return s;
  }
  const Vec3 n(0, 0, outside ? 1.0 : -1.0);
  const std::optional<Vec3> wi = refract(wo, n, eta_rel);
  if (!wi || wi->z == 0) return std::nullopt;  // F = 1 on TIR, so only reached by round-off
  const double T = 1.0 - F;
  // Radiance is compressed by (eta_wo / eta_wi)^2 = 1 / eta_rel^2 when it crosses into wo's
  // side (Veach 1997, Sec. 5.2); importance is not.
  const double scale = mode == TransportMode::kRadiance ? 1.0 / (eta_rel * eta_rel) : 1.0;
  s.wi = *wi;
  s.f = Rgb(T * scale / std::abs(wi->z));
  s.pdf = T;
  s.weight = Rgb(scale);
  s.flags = bsdf_flags::kTransmission | bsdf_flags::kDelta;
  s.eta_ratio = eta_rel;
  return s;
}

}  // namespace tb

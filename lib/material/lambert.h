// Lambertian reflection f = R / pi, two-sided (reflects on the side wo lies on).
#pragma once

#include "lib/material/bsdf.h"

namespace tb {

class LambertBsdf final : public Bsdf {
 public:
  explicit LambertBsdf(const Rgb& reflectance) : r_(reflectance) {}
  std::string_view name() const override { return "lambert"; }
  uint32_t flags() const override { return bsdf_flags::kReflection | bsdf_flags::kDiffuse; }
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  // Cosine-weighted hemisphere sampling (Malley's method on a concentric disk, Shirley & Chiu
  // 1997); pdf = |cos theta_i| / pi in solid angle.
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const override;
  double pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  Rgb eval_pdf(const Vec3& wo, const Vec3& wi, TransportMode mode, double* pdf) const override;
  double beckmann_roughness() const override { return kInfinity; }
  const Rgb& reflectance() const { return r_; }

 private:
  Rgb r_;
};

}  // namespace tb

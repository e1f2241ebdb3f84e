// Perfectly smooth dielectric interface (index eta inside, 1 outside; the normal points
// outside): Fresnel-weighted choice between mirror reflection and refraction (Snell). Both
// lobes are deltas. Transmission carries the (eta_wo / eta_wi)^2 radiance scaling in kRadiance
// mode and none in kImportance mode (Veach 1997, Sec. 5.2).
#pragma once

#include "lib/material/bsdf.h"

namespace tb {

class SmoothDielectricBsdf final : public Bsdf {
 public:
  explicit SmoothDielectricBsdf(double eta);
  std::string_view name() const override { return "smooth_dielectric"; }
  uint32_t flags() const override {
    return bsdf_flags::kReflection | bsdf_flags::kTransmission | bsdf_flags::kDelta;
  }
  Rgb eval(const Vec3&, const Vec3&, TransportMode) const override { return Rgb(0.0); }
  // uc < F picks reflection (probability F), otherwise refraction (probability 1 - F).
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const override;
  double pdf(const Vec3&, const Vec3&, TransportMode) const override { return 0.0; }
  double beckmann_roughness() const override { return 0.0; }
  double eta() const override { return eta_; }

 private:
  double eta_;
};

}  // namespace tb

// Perfectly smooth conductor: mirror reflection weighted by the exact conductor Fresnel term
// with complex index eta + i k per RGB channel. Two-sided. f and pdf are deltas: eval() and
// pdf() return 0, sample() returns the mirror direction with pdf 1 (discrete).
#pragma once

#include "lib/material/bsdf.h"

namespace tb {

class SmoothConductorBsdf final : public Bsdf {
 public:
  SmoothConductorBsdf(const Rgb& eta, const Rgb& k) : eta_(eta), k_(k) {}
  std::string_view name() const override { return "smooth_conductor"; }
  uint32_t flags() const override { return bsdf_flags::kReflection | bsdf_flags::kDelta; }
  Rgb eval(const Vec3&, const Vec3&, TransportMode) const override { return Rgb(0.0); }
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const override;
  double pdf(const Vec3&, const Vec3&, TransportMode) const override { return 0.0; }
  double beckmann_roughness() const override { return 0.0; }

 private:
  Rgb eta_, k_;
};

}  // namespace tb

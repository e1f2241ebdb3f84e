// Rough conductor: Torrance-Sparrow microfacet BRDF (Walter et al. 2007, Eq. 20)
//   f = F(<wo,m>) D(m) G2(wo, wi, m) / (4 |cos wo| |cos wi|),  m = normalize(wo + wi),
// with the exact conductor Fresnel term, Beckmann or GGX D, height-correlated G2. Two-sided.
// Sampling: m from D cos (Walter) or, for GGX, from the visible normals (Heitz 2018); then
// wi = reflect(wo, m) and pdf(wi) = pdf(m) / (4 <wo, m>) (Walter Eq. 14 / Kaplanyan Eq. 10).
#pragma once

#include "lib/core/microfacet.h"
#include "lib/material/bsdf.h"

namespace tb {

class RoughConductorBsdf final : public Bsdf {
 public:
  RoughConductorBsdf(const MicrofacetDistribution& dist, const Rgb& eta, const Rgb& k, bool visible_normals = false);
  std::string_view name() const override { return "rough_conductor"; }
  uint32_t flags() const override { return bsdf_flags::kReflection | bsdf_flags::kGlossy; }
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const override;
  double pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  double beckmann_roughness() const override { return dist_.beckmann_equivalent_alpha(); }
  const MicrofacetDistribution& distribution() const { return dist_; }
  bool visible_normals() const { return visible_; }

 private:
  MicrofacetDistribution dist_;
  Rgb eta_, k_;
  bool visible_;
};

}  // namespace tb

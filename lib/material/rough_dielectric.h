// Rough dielectric interface (index eta inside, 1 outside; the normal points outside): Walter
// et al. 2007 microfacet BSDF with Beckmann or GGX D and height-correlated G2.
//   reflection   f = F D G2 / (4 |cos wo| |cos wi|)                                 (Walter Eq. 20)
//   transmission f = |<wi,m>| |<wo,m>| eta_out^2 (1 - F) D G2
//                    / (|cos wi| |cos wo| (eta_wi <wi,m> + eta_wo <wo,m>)^2)         (Walter Eq. 21)
// with m the generalised half vector (lib/material/half_vector.h) and eta_out the index on the
// side the transported quantity leaves towards: eta_wo for kRadiance, eta_wi for kImportance
// (so f_imp(wo, wi) = f_rad(wi, wo), the adjoint BSDF; Veach 1997, Sec. 5.2).
// Sampling (Walter Sec. 5.3): m from D cos (or GGX visible normals), reflect with probability
// F(<wo, m>), otherwise refract; pdf = pdf(m) * {F, 1 - F} * |d omega_m / d omega_wi|.
#pragma once

#include "lib/core/microfacet.h"
#include "lib/material/bsdf.h"

namespace tb {

class RoughDielectricBsdf final : public Bsdf {
 public:
  RoughDielectricBsdf(const MicrofacetDistribution& dist, double eta, bool visible_normals = false);
  std::string_view name() const override { return "rough_dielectric"; }
  uint32_t flags() const override {
    return bsdf_flags::kReflection | bsdf_flags::kTransmission | bsdf_flags::kGlossy;
  }
  Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const override;
  double pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const override;
  double beckmann_roughness() const override { return dist_.beckmann_equivalent_alpha(); }
  double eta() const override { return eta_; }
  const MicrofacetDistribution& distribution() const { return dist_; }
  bool visible_normals() const { return visible_; }

 private:
  MicrofacetDistribution dist_;
  double eta_;
  bool visible_;
};

}  // namespace tb

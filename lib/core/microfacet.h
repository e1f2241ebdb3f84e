// Isotropic microfacet distributions: Beckmann and GGX (Walter, Marschner, Li, Torrance 2007,
// "Microfacet Models for Refraction through Rough Surfaces", EGSR). Directions and microfacet
// normals m live in the local shading frame (normal = +z); D is defined for m.z > 0.
//
// Normalisation: integral over the hemisphere of D(m) cos(theta_m) d omega_m = 1 (Walter Eq. 4).
// Masking-shadowing: Smith G1 from Lambda (Heitz 2014, "Understanding the Masking-Shadowing
// Function in Microfacet-Based BRDFs", JCGT 3(2), Sec. 5) and a HEIGHT-CORRELATED G2 (Heitz 2014,
// Sec. 6: Eq. 99 for reflection; for transmission the Beta-function form of the same section).
//
// Roughness: `alpha()` is the distribution's own parameter. The project's roughness is a
// Beckmann-equivalent alpha (Kaplanyan et al. 2014, Sec. 6): for GGX we use
//   alpha_ggx = sqrt(2) * alpha_beckmann,
// which matches the curvature of the slope density at its peak (the Laplace approximation:
// GGX's P22(x) = 1/(pi a^2 (1 + |x|^2/a^2)^2) ~ exp(-2|x|^2/a^2)/(pi a^2) near 0, i.e. a Gaussian
// of per-axis slope variance a^2/4; Beckmann's slope variance is alpha_b^2/2, Kaplanyan Sec. 6).
// GGX's slope variance itself is infinite (heavy tails), so the second moment cannot be matched.
#pragma once

#include <string_view>

#include "lib/core/frame.h"
#include "lib/core/math.h"

namespace tb {

enum class MicrofacetType { kBeckmann, kGgx };

std::string_view to_string(MicrofacetType t);
// "beckmann" or "ggx"; throws std::invalid_argument otherwise.
MicrofacetType microfacet_type_from_string(std::string_view s);

class MicrofacetDistribution {
 public:
  // alpha: the distribution's own width parameter (alpha_b or alpha_g of Walter 2007), > 0.
  MicrofacetDistribution(MicrofacetType type, double alpha);
  // From the project's Beckmann-equivalent roughness (see the header comment).
  static MicrofacetDistribution from_beckmann_equivalent(MicrofacetType type, double alpha_beckmann);
  static double ggx_alpha_from_beckmann(double alpha_beckmann) { return kSqrt2 * alpha_beckmann; }

  MicrofacetType type() const { return type_; }
  double alpha() const { return alpha_; }
  double beckmann_equivalent_alpha() const { return type_ == MicrofacetType::kGgx ? alpha_ / kSqrt2 : alpha_; }

  // Microfacet normal density D(m), per unit solid angle of m per unit macro-surface area
  // (Walter Eq. 25 Beckmann, Eq. 33 GGX). Zero for m.z <= 0.
  double D(const Vec3& m) const;
  // Smith Lambda(w); depends on |tan theta| only (Walter Eq. 27 + Heitz 2014 Sec. 5.3).
  double lambda(const Vec3& w) const;
  // Smith masking G1(w, m) = chi+((w.m)(w.n)) / (1 + Lambda(w)) (Walter Eq. 27 and 34).
  double G1(const Vec3& w, const Vec3& m) const;
  // Height-correlated masking-shadowing. Same side of the surface (reflection):
  // 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014 Eq. 99); opposite sides (transmission):
  // B(1 + Lambda(wo), 1 + Lambda(wi)), B the Beta function (Heitz 2014 Sec. 6: heights seen from
  // below are visible with probability (1 - C1(h))^Lambda). Symmetric in (wo, wi).
  double G2(const Vec3& wo, const Vec3& wi, const Vec3& m) const;

  // Samples m proportionally to D(m) cos(theta_m) (Walter Eq. 28-29, 35-36); always m.z > 0.
  Vec3 sample_m(const Vec2& u) const;
  // Density of sample_m in solid angle of m: D(m) |cos theta_m|.
  double pdf_m(const Vec3& m) const { return D(m) * std::abs(m.z); }

  // Visible-normal sampling (GGX only; Heitz 2018, "Sampling the GGX Distribution of Visible
  // Normals", JCGT 7(4), Listing 1): m ~ D_wo(m) = G1(wo, m) max(0, wo.m) D(m) / cos(theta_o)
  // (Heitz & d'Eon 2014, Eq. 2). Requires wo.z > 0.
  bool has_visible_sampling() const { return type_ == MicrofacetType::kGgx; }
  Vec3 sample_visible(const Vec3& wo, const Vec2& u) const;
  // Density of sample_visible in solid angle of m.
  double pdf_visible(const Vec3& wo, const Vec3& m) const;

 private:
  MicrofacetType type_;
  double alpha_;
};

}  // namespace tb

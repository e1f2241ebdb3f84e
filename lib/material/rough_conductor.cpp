#include "lib/material/rough_conductor.h"

#include <stdexcept>

#include "lib/material/fresnel.h"
#include "lib/material/half_vector.h"

namespace tb {

RoughConductorBsdf::RoughConductorBsdf(const MicrofacetDistribution& dist, const Rgb& eta, const Rgb& k,
                                       bool visible_normals)
    : dist_(dist), eta_(eta), k_(k), visible_(visible_normals) {
  if (visible_ && !dist_.has_visible_sampling())
    throw std::invalid_argument("rough_conductor: visible-normal sampling is only implemented for ggx");
}

Rgb RoughConductorBsdf::eval(const Vec3& wo_in, const Vec3& wi_in, TransportMode) const {
  if (wo_in.z * wi_in.z <= 0) return Rgb(0.0);
  const double s = wo_in.z > 0 ? 1.0 : -1.0;  // two-sided: work on wo's side
  const Vec3 wo = s * wo_in, wi = s * wi_in;
  const Vec3 m = generalized_half_vector(wi, wo, 1.0, 1.0);
  if (m.z <= 0) return Rgb(0.0);
  const double G = dist_.G2(wo, wi, m);
  if (G == 0) return Rgb(0.0);
  // Walter Eq. 20; the facet cosine averaged over wo and wi keeps f(wo,wi) == f(wi,wo) exactly.
  const double c = 0.5 * (glm::dot(wo, m) + glm::dot(wi, m));
  return fresnel_conductor(c, eta_, k_) * (dist_.D(m) * G / (4.0 * (wo.z * wi.z)));
}

double RoughConductorBsdf::pdf(const Vec3& wo_in, const Vec3& wi_in, TransportMode) const {
  if (wo_in.z * wi_in.z <= 0) return 0.0;
  const double s = wo_in.z > 0 ? 1.0 : -1.0;
  const Vec3 wo = s * wo_in, wi = s * wi_in;
  const Vec3 m = generalized_half_vector(wi, wo, 1.0, 1.0);
  const double wom = glm::dot(wo, m);
  if (m.z <= 0 || wom <= 0) return 0.0;
  const double pm = visible_ ? dist_.pdf_visible(wo, m) : dist_.pdf_m(m);
  // Solid angle of m per solid angle of wi: 1 / (4 <wi, m>) = half_vector_jacobian(wo, wi, 1, 1).
  return pm / (4.0 * wom);
}

std::optional<BsdfSample> RoughConductorBsdf::sample(const Vec3& wo_in, double, const Vec2& u,
                                                     TransportMode mode) const {
  if (wo_in.z == 0) return std::nullopt;
  const double s = wo_in.z > 0 ? 1.0 : -1.0;
  const Vec3 wo = s * wo_in;
  const Vec3 m = visible_ ? dist_.sample_visible(wo, u) : dist_.sample_m(u);
  if (glm::dot(wo, m) <= 0) return std::nullopt;  // D cos sampling can pick a back-facing facet
  const Vec3 wi = reflect(wo, m);
  if (wi.z <= 0) return std::nullopt;
  BsdfSample out;
  out.wi = s * wi;
  out.pdf = pdf(wo_in, out.wi, mode);
  out.f = eval(wo_in, out.wi, mode);
  if (!(out.pdf > 0)) return std::nullopt;
  out.weight = out.f * (std::abs(wi.z) / out.pdf);
  out.flags = bsdf_flags::kReflection | bsdf_flags::kGlossy;
  return out;
}

}  // namespace tb

#include "lib/material/rough_dielectric.h"

#include <stdexcept>

#include "lib/material/fresnel.h"
#include "lib/material/half_vector.h"

namespace tb {
namespace {

// The configuration seen from wo's side: both directions mirrored so that wo.z > 0, the index
// on wo's side normalised to 1 and the other side's index eta_rel = eta_other / eta_wo.
struct WoUpFrame {
  Vec3 wo, wi;
  double s;        // +1 or -1: the mirror applied
  double eta_rel;  // eta_other_side / eta_wo_side
};

WoUpFrame wo_up(const Vec3& wo, const Vec3& wi, double eta) {
  const double s = wo.z > 0 ? 1.0 : -1.0;
  return {s * wo, s * wi, s, wo.z > 0 ? eta : 1.0 / eta};
}

}  // namespace

RoughDielectricBsdf::RoughDielectricBsdf(const MicrofacetDistribution& dist, double eta, bool visible_normals)
    : dist_(dist), eta_(eta), visible_(visible_normals) {
  if (!(eta > 0) || !std::isfinite(eta)) throw std::invalid_argument("rough_dielectric: eta must be > 0");
  if (visible_ && !dist_.has_visible_sampling())
    throw std::invalid_argument("rough_dielectric: visible-normal sampling is only implemented for ggx");
}

Rgb RoughDielectricBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  if (wo.z == 0 || wi.z == 0) return Rgb(0.0);
  // Everything is computed symmetrically in (wo, wi), in the unmirrored frame, with the outside
  // direction first, so that reciprocity and the adjoint identity hold to the last bit rather
  // than up to round-off amplified by a steep D.
  const bool reflect = wo.z * wi.z > 0;
  const Vec3& w_out = wo.z > 0 ? wo : wi;  // outside (or, for reflection, either) direction
  const Vec3& w_in = wo.z > 0 ? wi : wo;
  const double eta_in = reflect ? 1.0 : eta_;
  const Vec3 m = generalized_half_vector(w_out, w_in, 1.0, eta_in);  // oriented to +z
  if (m.z <= 0) return Rgb(0.0);
  const double G = dist_.G2(wo, wi, m);  // symmetric; also rejects back-facing configurations
  if (G == 0) return Rgb(0.0);
  const double D = dist_.D(m);
  const double dot_out = glm::dot(w_out, m), dot_in = glm::dot(w_in, m);
  if (reflect) {
    // Both on one side: F at the (mathematically equal) facet cosine, averaged symmetrically.
    const double c = 0.5 * (std::abs(dot_out) + std::abs(dot_in));
    const double F = fresnel_dielectric(c, w_out.z > 0 ? eta_ : 1.0 / eta_);
    return Rgb(F * D * G / (4.0 * std::abs(wo.z * wi.z)));  // Walter Eq. 20
  }
  const double F = fresnel_dielectric(dot_out, eta_);  // F(outside cosine, eta) = F(inside cosine, 1/eta)
  // Walter Eq. 21: eta_o^2 of the medium the transported quantity leaves into: wo's medium for
  // radiance, wi's for importance; the denominator |H|^2 is symmetric.
  const double eta_wo = wo.z > 0 ? 1.0 : eta_, eta_wi = wi.z > 0 ? 1.0 : eta_;
  const double eta_leave = mode == TransportMode::kRadiance ? eta_wo : eta_wi;
  const double denom = sqr(dot_out + eta_in * dot_in);
  return Rgb(std::abs(dot_out * dot_in) * (1.0 - F) * D * G / (std::abs(wo.z * wi.z) * denom) * sqr(eta_leave));
}

double RoughDielectricBsdf::pdf(const Vec3& wo_in, const Vec3& wi_in, TransportMode) const {
  if (wo_in.z == 0 || wi_in.z == 0) return 0.0;
  const WoUpFrame c = wo_up(wo_in, wi_in, eta_);
  const bool reflect = c.wi.z > 0;
  const double eta_i = reflect ? 1.0 : c.eta_rel;
  const Vec3 m = generalized_half_vector(c.wi, c.wo, eta_i, 1.0);
  if (m.z <= 0) return 0.0;
  const double dot_o = glm::dot(c.wo, m), dot_i = glm::dot(c.wi, m);
  // sample() only produces wi from facets facing wo, on the matching side of the facet.
  if (dot_o <= 0 || (reflect ? dot_i <= 0 : dot_i >= 0)) return 0.0;
  const double pm = visible_ ? dist_.pdf_visible(c.wo, m) : dist_.pdf_m(m);
  const double F = fresnel_dielectric(dot_o, c.eta_rel);
  // |d omega_m / d omega_wi| at fixed wo (Kaplanyan et al. 2014, Eq. 10; Walter Eq. 14, 17).
  const double jac = half_vector_jacobian(c.wo, c.wi, 1.0, eta_i);
  return pm * (reflect ? F : 1.0 - F) * jac;
}

std::optional<BsdfSample> RoughDielectricBsdf::sample(const Vec3& wo_in, double uc, const Vec2& u,
                                                      TransportMode mode) const {
  if (wo_in.z == 0) return std::nullopt;
  const WoUpFrame c = wo_up(wo_in, Vec3(0.0), eta_);
  const Vec3 m = visible_ ? dist_.sample_visible(c.wo, u) : dist_.sample_m(u);
  const double dot_o = glm::dot(c.wo, m);
  if (dot_o <= 0) return std::nullopt;  // D cos sampling can pick a facet facing away from wo
  const double F = fresnel_dielectric(dot_o, c.eta_rel);
  BsdfSample out;
  Vec3 wi;
  if (uc < F) {
    wi = reflect(c.wo, m);
    if (wi.z <= 0) return std::nullopt;
    out.flags = bsdf_flags::kReflection | bsdf_flags::kGlossy;
  } else {
    const std::optional<Vec3> t = refract(c.wo, m, c.eta_rel);
    if (!t || t->z >= 0) return std::nullopt;
    wi = *t;
    out.flags = bsdf_flags::kTransmission | bsdf_flags::kGlossy;
    out.eta_ratio = c.eta_rel;
  }
  out.wi = c.s * wi;
  // Evaluate pdf and f from (wo, wi) so that sample(), pdf() and eval() agree exactly.
  out.pdf = pdf(wo_in, out.wi, mode);
  if (!(out.pdf > 0)) return std::nullopt;
  out.f = eval(wo_in, out.wi, mode);
  out.weight = out.f * (std::abs(wi.z) / out.pdf);
  return out;
}

}  // namespace tb

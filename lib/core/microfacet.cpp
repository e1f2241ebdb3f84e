#include "lib/core/microfacet.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace tb {

std::string_view to_string(MicrofacetType t) { return t == MicrofacetType::kBeckmann ? "beckmann" : "ggx"; }

MicrofacetType microfacet_type_from_string(std::string_view s) {
  if (s == "beckmann") return MicrofacetType::kBeckmann;
  if (s == "ggx") return MicrofacetType::kGgx;
  throw std::invalid_argument("unknown microfacet distribution '" + std::string(s) + "' (beckmann, ggx)");
}

MicrofacetDistribution::MicrofacetDistribution(MicrofacetType type, double alpha) : type_(type), alpha_(alpha) {
  if (!(alpha > 0) || !std::isfinite(alpha)) throw std::invalid_argument("microfacet alpha must be finite and > 0");
}

MicrofacetDistribution MicrofacetDistribution::from_beckmann_equivalent(MicrofacetType type, double alpha_beckmann) {
  return {type, type == MicrofacetType::kGgx ? ggx_alpha_from_beckmann(alpha_beckmann) : alpha_beckmann};
}

double MicrofacetDistribution::D(const Vec3& m) const {
  if (m.z <= 0) return 0.0;
  const double a2 = alpha_ * alpha_;
  const double cos2 = m.z * m.z;
  const double sin2 = std::max(0.0, m.x * m.x + m.y * m.y);
  if (type_ == MicrofacetType::kBeckmann) {
    // Walter Eq. 25: exp(-tan^2/a^2) / (pi a^2 cos^4).
    return std::exp(-sin2 / (cos2 * a2)) / (kPi * a2 * cos2 * cos2);
  }
  // Walter Eq. 33: a^2 / (pi cos^4 (a^2 + tan^2)^2) = a^2 / (pi (a^2 cos^2 + sin^2)^2),
  // the second form avoids tan^2 overflow at grazing m.
  const double d = a2 * cos2 + sin2;
  return a2 / (kPi * d * d);
}

double MicrofacetDistribution::lambda(const Vec3& w) const {
  const double sin2 = std::max(0.0, w.x * w.x + w.y * w.y);
  if (sin2 == 0) return 0.0;
  if (w.z == 0) return kInfinity;
  const double tan_t = std::sqrt(sin2) / std::abs(w.z);
  if (type_ == MicrofacetType::kBeckmann) {
    // Walter Eq. 27 with a = 1/(alpha tan): Lambda = (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi));
    // erfc keeps the cancellation accurate for large a.
    const double a = 1.0 / (alpha_ * tan_t);
    return 0.5 * (std::exp(-a * a) / (a * std::sqrt(kPi)) - std::erfc(a));
  }
  // GGX (Walter Eq. 34): Lambda = (-1 + sqrt(1 + alpha^2 tan^2)) / 2, written so that small
  // alpha tan loses no digits: (sqrt(1+x)-1)/2 = x / (2 (sqrt(1+x) + 1)).
  const double x = sqr(alpha_ * tan_t);
  if (!std::isfinite(x)) return kInfinity;
  return x / (2.0 * (std::sqrt(1.0 + x) + 1.0));
}

double MicrofacetDistribution::G1(const Vec3& w, const Vec3& m) const {
  if (glm::dot(w, m) * w.z <= 0) return 0.0;
  return 1.0 / (1.0 + lambda(w));
}

double MicrofacetDistribution::G2(const Vec3& wo, const Vec3& wi, const Vec3& m) const {
  if (glm::dot(wo, m) * wo.z <= 0 || glm::dot(wi, m) * wi.z <= 0) return 0.0;
  // Ordered so that G2(wo, wi) == G2(wi, wo) bit for bit (reciprocity tests compare exactly).
  const double l1 = lambda(wo), l2 = lambda(wi);
  const double lo = std::min(l1, l2), hi = std::max(l1, l2);
  if (!std::isfinite(hi)) return 0.0;
  if (wo.z * wi.z > 0) return 1.0 / (1.0 + lo + hi);  // Heitz 2014 Eq. 99
  // Transmission: integral over C1 in [0,1] of C1^Lambda_o (1 - C1)^Lambda_i = B(1+Lo, 1+Li).
  return std::beta(1.0 + lo, 1.0 + hi);
}

Vec3 MicrofacetDistribution::sample_m(const Vec2& u) const {
  const double a2 = alpha_ * alpha_;
  // tan^2(theta_m) by inverting the CDF of theta_m under D cos: Walter Eq. 28 (Beckmann,
  // -a^2 log(1 - u)) and Eq. 35 (GGX, a^2 u / (1 - u)); u < 1 so both are finite.
  const double one_minus_u = 1.0 - u.x;
  const double tan2 = type_ == MicrofacetType::kBeckmann ? -a2 * std::log(one_minus_u) : a2 * u.x / one_minus_u;
  const double cos_t = 1.0 / std::sqrt(1.0 + tan2);
  const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
  const double phi = 2.0 * kPi * u.y;  // Walter Eq. 29 / 36
  return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}

Vec3 MicrofacetDistribution::sample_visible(const Vec3& wo, const Vec2& u) const {
  // Heitz 2018, Listing 1: stretch wo to the alpha = 1 configuration, sample the projected
  // hemisphere of visible normals there, unstretch.
  const Vec3 vh = glm::normalize(Vec3(alpha_ * wo.x, alpha_ * wo.y, wo.z));
  const double lensq = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
  const Vec3 t2 = glm::cross(vh, t1);
  const double r = std::sqrt(u.x);
  const double phi = 2.0 * kPi * u.y;
  const double p1 = r * std::cos(phi);
  double p2 = r * std::sin(phi);
  const double s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * std::sqrt(std::max(0.0, 1.0 - p1 * p1)) + s * p2;
  const Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
  return glm::normalize(Vec3(alpha_ * nh.x, alpha_ * nh.y, std::max(1e-300, nh.z)));
}

double MicrofacetDistribution::pdf_visible(const Vec3& wo, const Vec3& m) const {
  if (wo.z <= 0) return 0.0;
  const double wom = glm::dot(wo, m);
  if (wom <= 0) return 0.0;
  return G1(wo, m) * wom * D(m) / wo.z;  // Heitz & d'Eon 2014, Eq. 2
}

}  // namespace tb

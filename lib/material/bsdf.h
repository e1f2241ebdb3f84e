// The BSDF interface. All directions are in the local shading frame (tb::Frame, normal = +z,
// cos theta = w.z), both pointing AWAY from the surface. `wo` is the direction the path arrived
// from (towards the camera when tracing radiance, towards the light when tracing importance),
// `wi` the direction being sampled or evaluated.
//
// Why a virtual interface and not a std::variant: BSDFs are an open set of components chosen by
// name from a registry (STYLE.md: variants are separate registered components), scenes hold them
// behind one pointer type, and adding one must not edit a central type list. The virtual call is
// negligible next to the microfacet math (see bench/material_bench.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "lib/core/frame.h"
#include "lib/core/math.h"
#include "lib/core/spectrum.h"

namespace tb {

// Which quantity flows along the path (Veach 1997, Ch. 5.2). Light physically flows wi -> wo
// in kRadiance mode and wo -> wi in kImportance mode; the two differ only for refraction, where
// the BTDF is not symmetric: f_rad(wo, wi) / eta_wo^2 = f_rad(wi, wo) / eta_wi^2 (Veach 1997,
// Sec. 5.2), and the adjoint BSDF is f_imp(wo, wi) = f_rad(wi, wo) (Veach 1997, Sec. 3.7).
enum class TransportMode { kRadiance, kImportance };

namespace bsdf_flags {
inline constexpr uint32_t kReflection = 1u << 0;
inline constexpr uint32_t kTransmission = 1u << 1;
inline constexpr uint32_t kDiffuse = 1u << 2;
inline constexpr uint32_t kGlossy = 1u << 3;
inline constexpr uint32_t kDelta = 1u << 4;  // specular: f and pdf are Dirac deltas
}  // namespace bsdf_flags

struct BsdfSample {
  Vec3 wi{0, 0, 1};
  // BSDF value. For a delta lobe: the coefficient c of c * delta(wi - w*)/|cos wi| is reported as
  // f = c / |cos wi|, i.e. what a renderer multiplies by |cos wi| / pdf.
  Rgb f{0.0};
  // f |cos wi| / pdf: the path throughput factor.
  Rgb weight{0.0};
  // Density of wi in solid angle (non-delta lobes) or the discrete probability of the chosen
  // delta lobe (delta lobes).
  double pdf = 0.0;
  uint32_t flags = 0;
  // eta_wi / eta_wo: ratio of the refractive indices on the wi and wo sides (1 for reflection).
  double eta_ratio = 1.0;

  bool is_delta() const { return (flags & bsdf_flags::kDelta) != 0; }
  bool is_transmission() const { return (flags & bsdf_flags::kTransmission) != 0; }
};

class Bsdf {
 public:
  virtual ~Bsdf() = default;

  virtual std::string_view name() const = 0;
  // Union of the flags of all lobes.
  virtual uint32_t flags() const = 0;

  // f(wo, wi), per steradian. Zero whenever wi lies on a delta lobe (deltas are only sampled).
  virtual Rgb eval(const Vec3& wo, const Vec3& wi, TransportMode mode) const = 0;
  // Samples wi given wo from uniforms: uc picks the lobe (reflection / transmission), u the
  // direction. Empty when no direction is produced (e.g. a microfacet normal facing away).
  virtual std::optional<BsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const = 0;
  // Density of sample() producing wi, in solid angle of wi (zero on delta lobes). Integrates to
  // the probability that sample() succeeds with a non-delta lobe (at most 1).
  virtual double pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const = 0;
  // eval() and pdf() of the same pair in one call (next-event estimation needs both): *pdf =
  // pdf(wo, wi, mode), returns eval(wo, wi, mode), bit for bit. Overridden where one call is
  // cheaper than two virtual calls.
  virtual Rgb eval_pdf(const Vec3& wo, const Vec3& wi, TransportMode mode, double* pdf) const {
    *pdf = this->pdf(wo, wi, mode);
    return eval(wo, wi, mode);
  }

  // Beckmann-equivalent roughness alpha (Kaplanyan et al. 2014, Sec. 6): 0 for delta BSDFs,
  // +inf for diffuse ones.
  virtual double beckmann_roughness() const = 0;
  // Refractive index inside / outside (the normal points outside); 1 for opaque BSDFs.
  virtual double eta() const { return 1.0; }
};

// Shared helpers of the BSDF implementations (local frame).
inline Vec3 reflect(const Vec3& w, const Vec3& n) { return -w + 2.0 * glm::dot(w, n) * n; }

// Refracts w (pointing away from the surface, on the side n points to) through the interface
// with normal n; eta = eta_other_side / eta_w_side. Empty on total internal reflection.
inline std::optional<Vec3> refract(const Vec3& w, const Vec3& n, double eta) {
  const double cos_i = glm::dot(w, n);
  const double sin2_t = std::max(0.0, 1.0 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0) return std::nullopt;
  const double cos_t = std::sqrt(1.0 - sin2_t);
  return -w / eta + (cos_i / eta - cos_t) * n;  // Snell's law, vector form
}

}  // namespace tb

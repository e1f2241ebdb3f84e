#include "lib/path/dirac.h"

#include <cmath>

namespace tb {

namespace {

double channel_sum(const Rgb& c) { return c.r + c.g + c.b; }

}  // namespace

bool is_dirac_surface(const PathVertex& v) {
  if (!v.is_surface() || !v.bsdf) return false;
  const uint32_t fl = v.bsdf->flags();
  return (fl & bsdf_flags::kDelta) != 0 && (fl & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy)) == 0;
}

bool is_dirac_transmission(const PathVertex& v, const Vec3& wo, const Vec3& wi) {
  return glm::dot(wo, v.hit.ng) * glm::dot(wi, v.hit.ng) < 0.0;
}

std::optional<WorldBsdfSample> dirac_lobe_sample(const PathVertex& v, const Vec3& wo, bool transmission,
                                                 TransportMode mode) {
  if (!is_dirac_surface(v)) return std::nullopt;
  // uc picks the lobe (Bsdf::sample): reflection for uc below the reflection probability, so uc = 0
  // is reflection and the largest double below 1 transmission (when it has positive probability).
  const double uc = transmission ? std::nextafter(1.0, 0.0) : 0.0;
  const auto s = SurfaceScatter(v.hit, *v.bsdf).sample(wo, uc, Vec2(0.5), mode);
  if (!s || !s->is_delta() || ((s->flags & bsdf_flags::kTransmission) != 0) != transmission) return std::nullopt;
  if (!(s->pdf > 0.0) || is_black(s->f)) return std::nullopt;
  return s;
}

std::optional<WorldBsdfSample> dirac_lobe(const PathVertex& v, const Vec3& wo, const Vec3& wi, TransportMode mode) {
  const auto s = dirac_lobe_sample(v, wo, is_dirac_transmission(v, wo, wi), mode);
  if (!s || !(1.0 - glm::dot(s->wi, wi) <= kDiracCosTolerance)) return std::nullopt;
  return s;
}

double pdf_next_dirac(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                      TransportMode mode, DiracLobeChoice choice) {
  if (!prev || !is_dirac_surface(cur)) return pdf_next(ctx, prev, cur, next, mode);
  const Vec3 wp = direction(cur, *prev), wn = direction(cur, next);
  const auto s = dirac_lobe(cur, wp, wn, mode);
  if (!s) return 0.0;
  double p = choice == DiracLobeChoice::kSampled ? s->pdf : 1.0;
  if (mode == TransportMode::kImportance) {
    // The delta of an importance-mode step is in the camera-side direction: convert it to the
    // light-side delta of f_s (see the header). The ratio is of the BSDF values without the
    // shading-normal factor of the adjoint (s->f carries it): p = P_imp f_s(c -> l) / f*_s(l -> c)
    // makes f(X) / p the light subpath's weight (docs/path.md, Shading normals; Veach 1997, Eq. 5.19).
    const auto r = dirac_lobe(cur, wn, wp, TransportMode::kRadiance);
    const double den = channel_sum(s->f);
    const double corr = importance_shading_correction(cur.hit, wp, wn);
    if (!r || !(den > 0.0) || !(corr > 0.0)) return 0.0;
    p *= channel_sum(r->f) * corr / den;
  }
  return to_area(p, cur, next);
}

Rgb dirac_f(const PathVertex& b, const Vec3& wo, const Vec3& wi) {
  const auto s = dirac_lobe(b, wo, wi, TransportMode::kRadiance);
  return s ? s->f : Rgb(0.0);
}

}  // namespace tb

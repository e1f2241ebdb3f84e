// Scattering at a surface vertex in world space, shared by every integrator and mutation so
// that all of them evaluate the same f and the same densities:
//  - two-sided shading for BSDFs without transmission: the shading frame is flipped to the side
//    of the geometric normal that `wo` lies on; f is zero unless wi lies on that side of the
//    geometric normal too (no light leaks through shading normals);
//  - the shading-normal correction of the adjoint BSDF for importance transport (Veach 1997,
//    Sec. 5.3.2, Eq. 5.19; pbrt-v3 Sec. 16.1.3): f_imp is multiplied by
//    |wo.n| |wi.ng| / (|wo.ng| |wi.n|), wo the light side, so that light tracing and the light
//    subpaths of BDPT estimate the measurement path tracing estimates when n != ng (derivation
//    in docs/path.md, "Shading normals");
//  - cosines: a contribution uses |wi.n| (shading normal) for the projected solid angle at a
//    surface vertex; density conversions to area use the geometric normal (measure.h).
// Directions: wo is where the path came from, wi where it goes, both unit and pointing away.
#pragma once

#include <optional>

#include "lib/core/frame.h"
#include "lib/geometry/hit.h"
#include "lib/material/bsdf.h"

namespace tb {

// The factor f_imp(wo -> wi) / f*_s(wo -> wi) = |wo.n| |wi.ng| / (|wo.ng| |wi.n|) at `hit` (n the
// shading normal, wo the light-side direction, wi the camera-side one; Veach 1997, Eq. 5.19).
// Exactly 1 where n == ng; 0 where |wo.ng| |wi.n| = 0.
double importance_shading_correction(const SurfacePoint& hit, const Vec3& wo, const Vec3& wi);

// The shading-normal factor a SurfaceScatter applies in importance transport: Veach's
// importance_shading_correction in every integrator; a negative control (validate/) passes a
// wrong one.
using ImportanceCorrection = double (*)(const SurfacePoint& hit, const Vec3& wo, const Vec3& wi);

struct WorldBsdfSample {
  Vec3 wi{0.0};
  Rgb f{0.0};       // corrected BSDF value (delta lobes: coefficient / |cos|, as BsdfSample::f)
  Rgb weight{0.0};  // f |wi.n| / pdf
  double pdf = 0.0; // solid angle (delta lobes: discrete lobe probability)
  uint32_t flags = 0;
  bool is_delta() const { return (flags & bsdf_flags::kDelta) != 0; }
};

class SurfaceScatter {
 public:
  // `hit` (a Hit or a SurfacePoint) must outlive the object.
  SurfaceScatter(const SurfacePoint& hit, const Bsdf& bsdf,
                 ImportanceCorrection correction = &importance_shading_correction)
      : hit_(&hit), bsdf_(&bsdf), flags_(bsdf.flags()), correction_(correction) {}

  Rgb f(const Vec3& wo, const Vec3& wi, TransportMode mode) const;
  double pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const;
  // f(wo, wi, mode), with *pdf = pdf(wo, wi, mode): one frame look-up and one BSDF call.
  Rgb f_pdf(const Vec3& wo, const Vec3& wi, TransportMode mode, double* pdf) const;
  std::optional<WorldBsdfSample> sample(const Vec3& wo, double uc, const Vec2& u, TransportMode mode) const;

  // |w . n| with the shading normal.
  double abs_cos_shading(const Vec3& w) const { return std::abs(glm::dot(w, hit_->n)); }
  const Bsdf& bsdf() const { return *bsdf_; }
  uint32_t flags() const { return flags_; }  // == bsdf().flags()
  const SurfacePoint& hit() const { return *hit_; }

 private:
  // The shading frame on wo's side, built at most once per side (f, pdf and sample at one vertex
  // share it). Inline: after the first call this is a dot product and a bit test.
  const Frame& frame_for(const Vec3& wo) const {
    const bool transmissive = (flags_ & bsdf_flags::kTransmission) != 0;
    const unsigned side = (!transmissive && glm::dot(wo, hit_->ng) < 0) ? 1u : 0u;
    if (!(built_ & (1u << side))) build_frame(side);
    return frames_[side].frame;
  }
  void build_frame(unsigned side) const;
  double correction(const Vec3& wo, const Vec3& wi, TransportMode mode) const;
  bool sides_ok(const Vec3& wo, const Vec3& wi) const;
  const SurfacePoint* hit_;
  const Bsdf* bsdf_;
  uint32_t flags_;              // bsdf_->flags(), read once (a virtual call)
  ImportanceCorrection correction_;  // importance_shading_correction except in a negative control
  // Storage for a frame that is left uninitialised until build_frame constructs it: two
  // default-constructed Frames (18 doubles) would otherwise be written for every vertex.
  union FrameSlot {
    FrameSlot() {}
    Frame frame;
  };
  mutable FrameSlot frames_[2];  // [0]: from_z(n), [1]: from_z(-n), valid where built_ says
  mutable unsigned built_ = 0;  // bit i: frames_[i] is built
};

// Inline: the caller reads the sample's fields straight from registers. Out of line, the record
// was read back with 16-byte loads over the callee's 8-byte stores (a store-forwarding stall on
// every bounce of the path tracer, ~7 % of its loop's samples in perf).
inline std::optional<WorldBsdfSample> SurfaceScatter::sample(const Vec3& wo, double uc, const Vec2& u,
                                                             TransportMode mode) const {
  const Frame& fr = frame_for(wo);
  const auto bs = bsdf_->sample(fr.to_local(wo), uc, u, mode);
  if (!bs || !(bs->pdf > 0)) return std::nullopt;
  // The frame is orthonormal and bs->wi a unit vector, so wi is unit to a few ulps: no
  // normalisation (its square root and division sat on the chain to the next ray).
  const Vec3 wi = fr.to_world(bs->wi);
  // Returned as prvalues built in place from every field (see LambertBsdf::sample for why).
  if (!sides_ok(wo, wi)) return std::optional<WorldBsdfSample>(std::in_place, wi, Rgb(0.0), Rgb(0.0), bs->pdf, bs->flags);
  const double c = correction(wo, wi, mode);
  // bs->weight = f |cos wi| / pdf with the (possibly flipped) shading normal
  return std::optional<WorldBsdfSample>(std::in_place, wi, bs->f * c, bs->weight * c, bs->pdf, bs->flags);
}

}  // namespace tb

#include "lib/path/scattering.h"

#include <cmath>
#include <memory>
#include <utility>

namespace tb {

void SurfaceScatter::build_frame(unsigned side) const {
  std::construct_at(&frames_[side].frame, Frame::from_z(side ? -hit_->n : hit_->n));
  built_ |= 1u << side;
}

bool SurfaceScatter::sides_ok(const Vec3& wo, const Vec3& wi) const {
  if (flags_ & bsdf_flags::kTransmission) return true;
  return glm::dot(wo, hit_->ng) * glm::dot(wi, hit_->ng) > 0;
}

double importance_shading_correction(const SurfacePoint& hit, const Vec3& wo, const Vec3& wi) {
  // Veach 1997, Eq. 5.19 with wo = l (towards the light side), wi = c (towards the camera side):
  // f_imp(l -> c) |c.n| = f*_s(l -> c) |l.n| |c.ng| / |l.ng|, the measurement's factor at the
  // vertex over the |l.ng| of the light subpath's area density (docs/path.md, Shading normals).
  const double num = std::abs(glm::dot(wo, hit.n)) * std::abs(glm::dot(wi, hit.ng));
  const double den = std::abs(glm::dot(wo, hit.ng)) * std::abs(glm::dot(wi, hit.n));
  if (num == den) return 1.0;  // n == ng: exactly 1, no rounding
  return den > 0 ? num / den : 0.0;
}

double SurfaceScatter::correction(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  if (mode != TransportMode::kImportance) return 1.0;
  return correction_(*hit_, wo, wi);
}

Rgb SurfaceScatter::f(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  if (!sides_ok(wo, wi)) return Rgb(0.0);
  const Frame& fr = frame_for(wo);
  return bsdf_->eval(fr.to_local(wo), fr.to_local(wi), mode) * correction(wo, wi, mode);
}

Rgb SurfaceScatter::f_pdf(const Vec3& wo, const Vec3& wi, TransportMode mode, double* pdf) const {
  const Frame& fr = frame_for(wo);
  const Rgb f = bsdf_->eval_pdf(fr.to_local(wo), fr.to_local(wi), mode, pdf);
  if (!sides_ok(wo, wi)) return Rgb(0.0);
  return f * correction(wo, wi, mode);
}

double SurfaceScatter::pdf(const Vec3& wo, const Vec3& wi, TransportMode mode) const {
  const Frame& fr = frame_for(wo);
  return bsdf_->pdf(fr.to_local(wo), fr.to_local(wi), mode);
}

}  // namespace tb

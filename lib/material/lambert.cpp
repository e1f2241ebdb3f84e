#include "lib/material/lambert.h"

#include "lib/core/warp_disk.h"

namespace tb {
namespace {

// Shirley & Chiu 1997 concentric map of [0,1)^2 to the unit disk, lifted to the hemisphere
// (Malley's method): density |cos theta| / pi in solid angle.
Vec3 cosine_hemisphere(const Vec2& u) {
  const Vec2 d = sample_uniform_disk_concentric(u);
  return {d.x, d.y, safe_sqrt(1.0 - d.x * d.x - d.y * d.y)};
}

}  // namespace

Rgb LambertBsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (wo.z * wi.z <= 0) return Rgb(0.0);
  return r_ * kInvPi;
}

std::optional<BsdfSample> LambertBsdf::sample(const Vec3& wo, double, const Vec2& u, TransportMode) const {
  if (wo.z == 0) return std::nullopt;
  Vec3 wi = cosine_hemisphere(u);
  if (wi.z == 0) return std::nullopt;  // measure-zero rim of the disk
  if (wo.z < 0) wi.z = -wi.z;
  // Returned as a prvalue built in place from every field (guaranteed elision): a local BsdfSample
  // copied into the optional was read back with wider loads than it was written with (a
  // store-forwarding stall on every sample), and a default-constructed optional is zero-filled.
  return std::optional<BsdfSample>(std::in_place, wi, r_ * kInvPi, r_ /* f |cos| / pdf = R exactly */,
                                   std::abs(wi.z) * kInvPi, bsdf_flags::kReflection | bsdf_flags::kDiffuse, 1.0);
}

Rgb LambertBsdf::eval_pdf(const Vec3& wo, const Vec3& wi, TransportMode, double* pdf) const {
  if (wo.z * wi.z <= 0) {
    *pdf = 0.0;
    return Rgb(0.0);
  }
  *pdf = std::abs(wi.z) * kInvPi;
  return r_ * kInvPi;
}

double LambertBsdf::pdf(const Vec3& wo, const Vec3& wi, TransportMode) const {
  if (wo.z * wi.z <= 0) return 0.0;
  return std::abs(wi.z) * kInvPi;
}

}  // namespace tb

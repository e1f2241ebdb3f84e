#include "lib/mcmc/path_space/lens_perturbation.h"

#include <algorithm>
#include <cmath>

namespace tb::path_space {

LensPerturbation::LensPerturbation(const PathContext& ctx, double r1, double r2, LensFault fault)
    : ctx_(&ctx), r1_(r1), r2_(r2), fault_(fault) {
  const Camera& cam = ctx.world->camera();
  if (!(r2_ > 0.0)) r2_ = 0.1 * std::max(cam.width(), cam.height());
  if (!(r2_ > r1_)) r2_ = 2.0 * r1_;
}

bool LensPerturbation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 1 || x.v[k].kind != VertexKind::kCamera || !ctx_->world->camera().lens_is_delta()) return false;
  const PathVertex& v = x.v[k - 1];
  // k = 1: x_0 is the emitter seen directly (a surface hit or an emitter-sampled point).
  if (k == 1 && v.is_light_kind()) return !v.delta && !v.infinite;
  return v.is_surface() && !v.delta;
}

Vec2 LensPerturbation::sample_offset(const Vec2& u) const {
  const double phi = 2.0 * kPi * u.x;
  const double r = r2_ * std::exp(-std::log(r2_ / r1_) * u.y);
  return {r * std::cos(phi), r * std::sin(phi)};
}

double LensPerturbation::kernel_density(const Vec2& d) const {
  const double r2 = glm::dot(d, d);
  if (!(r2 >= r1_ * r1_) || !(r2 <= r2_ * r2_)) return 0.0;
  return 1.0 / (2.0 * kPi * r2 * std::log(r2_ / r1_));
}

std::optional<MltPath> LensPerturbation::perturb(const MltPath& x, const Vec2& offset) const {
  if (!applicable(x)) return std::nullopt;
  const auto rx = path_raster(*ctx_, x);
  if (!rx) return std::nullopt;
  const Vec2 ry = *rx + offset;
  const Camera& cam = ctx_->world->camera();
  if (!cam.projection().inside(ry)) return std::nullopt;
  const CameraRay cr = cam.generate_ray(ry, Vec2(0.5));
  const int k = x.segments();
  const auto hit = ctx_->world->geometry().intersect(Ray{x.v[k].hit.p, cr.ray.d});
  if (!hit) return std::nullopt;
  PathVertex v;
  v.kind = VertexKind::kSurface;
  v.hit = *hit;
  const SurfaceInfo& si = ctx_->world->surface(hit->shape_id);
  v.bsdf = si.bsdf;
  v.light = si.emitter;
  MltPath y = x;
  y.v[k - 1] = v;
  return y;
}

std::optional<MltPath> LensPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 uo = u.next2();
  return perturb(x, sample_offset(uo));
}

double LensPerturbation::raster_jacobian(const MltPath& x) const {
  const int k = x.segments();
  return static_cast<double>(ctx_->world->camera().pixel_count()) *
         pdf_next(*ctx_, nullptr, x.v[k], x.v[k - 1], TransportMode::kRadiance);
}

double LensPerturbation::density(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return 0.0;
  for (int i = 0; i <= k; ++i)
    if (i != k - 1 && !same_vertex(x.v[i], y.v[i])) return 0.0;
  const auto rx = path_raster(*ctx_, x), ry = path_raster(*ctx_, y);
  if (!rx || !ry) return 0.0;
  const double kern = kernel_density(*ry - *rx);
  if (fault_ == LensFault::kDropDensityRatio) return kern > 0.0 ? 1.0 : 0.0;
  return kern * raster_jacobian(y);
}

}  // namespace tb::path_space

#include "lib/mcmc/path_space/lens_perturbation.h"

#include <algorithm>
#include <cmath>

#include "lib/geometry/spawn.h"
#include "lib/path/dirac.h"

namespace tb::path_space {

LensPerturbation::LensPerturbation(const PathContext& ctx, double r1, double r2) : ctx_(&ctx), r1_(r1), r2_(r2) {
  const Camera& cam = ctx.world->camera();
  if (!(r2_ > 0.0)) r2_ = 0.1 * std::max(cam.width(), cam.height());
  if (!(r2_ > r1_)) r2_ = 2.0 * r1_;
}

int LensPerturbation::chain_end(const MltPath& x) const {
  int j = x.segments() - 1;
  while (j >= 0 && is_dirac_surface(x.v[j])) --j;
  return j;
}

bool LensPerturbation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 1 || x.v[k].kind != VertexKind::kCamera || !ctx_->world->camera().lens_is_delta()) return false;
  const int j = chain_end(x);
  if (j < 0) return false;
  const PathVertex& v = x.v[j];
  // j = 0: x_0 is the emitter seen (through the chain): a surface hit or an emitter-sampled point.
  if (j == 0) return v.is_light_kind() ? !v.delta && !v.infinite : v.is_surface() && !v.delta;
  return v.is_surface() && !v.delta && !is_dirac_surface(x.v[j - 1]);
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
  return trace(x, offset);
}

std::optional<MltPath> LensPerturbation::trace(const MltPath& x, const Vec2& offset) const {
  const auto rx = path_raster(*ctx_, x);
  if (!rx) return std::nullopt;
  const Vec2 ry = *rx + offset;
  const Camera& cam = ctx_->world->camera();
  if (!cam.projection().inside(ry)) return std::nullopt;
  const CameraRay cr = cam.generate_ray(ry, Vec2(0.5));
  const int k = x.segments(), j = chain_end(x);
  if (j < 0) return std::nullopt;
  const auto hit = ctx_->world->geometry().intersect(Ray{x.v[k].hit.p, cr.ray.d});
  if (!hit) return std::nullopt;
  MltPath y = x;
  y.v[k - 1] = surface_vertex(*ctx_, *hit);
  // Through the specular chain, each vertex with its lobe in x (Veach 1997, Sec. 11.4.3).
  for (int i = k - 1; i > j; --i) {
    if (!is_dirac_surface(y.v[i])) return std::nullopt;
    const auto s = dirac_lobe_sample(y.v[i], direction(y.v[i], y.v[i + 1]), transmits_from_camera_side(x, i), TransportMode::kRadiance);
    if (!s) return std::nullopt;
    const auto h = ctx_->world->geometry().intersect(spawn_ray(y.v[i].hit, s->wi));
    if (!h) return std::nullopt;
    y.v[i - 1] = surface_vertex(*ctx_, *h);
  }
  if (is_dirac_surface(y.v[j])) return std::nullopt;
  return y;
}

std::optional<MltPath> LensPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 uo = u.next2();
  return perturb(x, sample_offset(uo));
}

double LensPerturbation::raster_jacobian(const MltPath& x) const {
  const int k = x.segments(), j = chain_end(x);
  double p = static_cast<double>(ctx_->world->camera().pixel_count()) *
             pdf_next(*ctx_, nullptr, x.v[k], x.v[k - 1], TransportMode::kRadiance);
  for (int i = k - 1; i > j; --i)
    p *= pdf_next_dirac(*ctx_, &x.v[i + 1], x.v[i], x.v[i - 1], TransportMode::kRadiance, DiracLobeChoice::kKept);
  return p;
}

double LensPerturbation::density(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return 0.0;
  const int j = chain_end(x);
  if (chain_end(y) != j) return 0.0;
  for (int i = 0; i <= k; ++i)
    if ((i < j || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  for (int i = k - 1; i > j; --i)
    if (transmits_from_camera_side(x, i) != transmits_from_camera_side(y, i)) return 0.0;
  const auto rx = path_raster(*ctx_, x), ry = path_raster(*ctx_, y);
  if (!rx || !ry) return 0.0;
  const double kern = kernel_density(*ry - *rx);
  return kern * raster_jacobian(y);
}

}  // namespace tb::path_space

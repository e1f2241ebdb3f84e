#include "lib/mcmc/path_space/multi_chain_perturbation.h"

#include <cmath>

#include "lib/core/frame.h"
#include "lib/geometry/spawn.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"

namespace tb::path_space {

// The direction from the apex at x_i (spawn_ray's origin towards x_{i-1}) to x_{i-1}.
Vec3 apex_direction(const MltPath& x, int i) {
  const Vec3 o = spawn_ray(x.v[i].hit, direction(x.v[i], x.v[i - 1])).o;
  return glm::normalize(x.v[i - 1].hit.p - o);
}

// Traces from y_i (already placed) along w through the specular chain of x below i (lobes kept)
// to the next non-specular index `stop`; fills y_{i-1} .. y_stop. False when the chain changes.
bool trace_chain(const PathContext& ctx, const MltPath& x, MltPath& y, int i, Vec3 w, int stop) {
  for (int c = i; c > stop; --c) {
    const auto h = ctx.world->geometry().intersect(spawn_ray(y.v[c].hit, w));
    if (!h) return false;
    y.v[c - 1] = surface_vertex(ctx, *h);
    if (c - 1 == stop) break;
    if (!is_dirac_surface(y.v[c - 1])) return false;
    const auto s = dirac_lobe_sample(y.v[c - 1], -w, transmits_from_camera_side(x, c - 1), TransportMode::kRadiance);
    if (!s) return false;
    w = s->wi;
  }
  return !is_dirac_surface(y.v[stop]);
}

std::vector<int> MultiChainPerturbation::levels(const MltPath& x) const {
  if (!ctx_->world->camera().lens_is_delta()) return {};
  return multi_chain_levels(x);
}

std::vector<int> multi_chain_levels(const MltPath& x) {
  const int k = x.segments();
  std::vector<int> out;
  if (k < 3 || x.v[k].kind != VertexKind::kCamera) return out;
  int j = k - 1;
  while (j >= 0 && is_dirac_surface(x.v[j])) --j;
  if (j < 1 || !x.v[j].is_surface() || x.v[j].bsdf == nullptr || !is_dirac_surface(x.v[j - 1])) return out;
  for (;;) {
    out.push_back(j);
    if (j == 0) break;
    if (!is_dirac_surface(x.v[j - 1])) break;  // joined to the kept x_{j-1}
    if (!x.v[j].is_surface() || x.v[j].bsdf == nullptr) return {};
    int n = j - 1;
    while (n >= 0 && is_dirac_surface(x.v[n])) --n;
    if (n < 0) return {};
    j = n;
  }
  const PathVertex& last = x.v[out.back()];
  if (out.back() == 0 && (last.infinite || last.delta || !last.light)) return {};
  return out;
}

double MultiChainPerturbation::angular_density(double theta) const {
  if (!(theta >= theta1_) || !(theta <= theta2_)) return 0.0;
  return 1.0 / (2.0 * kPi * std::sin(theta) * theta * std::log(theta2_ / theta1_));
}

std::optional<MltPath> MultiChainPerturbation::perturb(const MltPath& x, const Vec2& offset,
                                                       const std::vector<Vec2>& theta_phi) const {
  const std::vector<int> lv = levels(x);
  if (lv.empty() || theta_phi.size() + 1 < lv.size()) return std::nullopt;
  const int k = x.segments();
  const auto rx = path_raster(*ctx_, x);
  if (!rx) return std::nullopt;
  const Vec2 ry = *rx + offset;
  const Camera& cam = ctx_->world->camera();
  if (!cam.projection().inside(ry)) return std::nullopt;
  const CameraRay cr = cam.generate_ray(ry, Vec2(0.5));
  MltPath y = x;
  // First chain: from the camera (the camera vertex is not a surface; trace its ray directly).
  const auto h = ctx_->world->geometry().intersect(Ray{x.v[k].hit.p, cr.ray.d});
  if (!h) return std::nullopt;
  y.v[k - 1] = surface_vertex(*ctx_, *h);
  if (k - 1 > lv[0]) {
    if (!is_dirac_surface(y.v[k - 1])) return std::nullopt;
    const auto s = dirac_lobe_sample(y.v[k - 1], -cr.ray.d, transmits_from_camera_side(x, k - 1), TransportMode::kRadiance);
    if (!s || !trace_chain(*ctx_, x, y, k - 1, s->wi, lv[0])) return std::nullopt;
  } else if (is_dirac_surface(y.v[k - 1])) {
    return std::nullopt;
  }
  // Each continued level: perturb the old direction at the new vertex, trace the next chain.
  for (size_t m = 0; m + 1 < lv.size(); ++m) {
    const int i = lv[m];
    const Vec3 wx = apex_direction(x, i);
    const Frame fr = Frame::from_z(wx);
    const double th = theta_phi[m].x, ph = theta_phi[m].y, st = std::sin(th);
    const Vec3 wy = glm::normalize(fr.to_world(Vec3(st * std::cos(ph), st * std::sin(ph), std::cos(th))));
    // The scattering side at y_i must be that of x_i (reflection / transmission kept).
    const Vec3 cx = direction(x.v[i], x.v[i + 1]), cy = direction(y.v[i], y.v[i + 1]);
    const bool tx = glm::dot(cx, x.v[i].hit.ng) * glm::dot(wx, x.v[i].hit.ng) < 0;
    const bool ty = glm::dot(cy, y.v[i].hit.ng) * glm::dot(wy, y.v[i].hit.ng) < 0;
    if (tx != ty) return std::nullopt;
    if (!trace_chain(*ctx_, x, y, i, wy, lv[m + 1])) return std::nullopt;
  }
  return y;
}

std::optional<MltPath> MultiChainPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 uo = u.next2();
  std::vector<Vec2> tp(static_cast<size_t>(std::max(0, x.segments())));  // fixed uniform count per length
  for (auto& t : tp) {
    const Vec2 ua = u.next2();
    t = Vec2(theta2_ * std::exp(-std::log(theta2_ / theta1_) * ua.x), 2.0 * kPi * ua.y);
  }
  return perturb(x, lens_.sample_offset(uo), tp);
}

double MultiChainPerturbation::density(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  if (y.segments() != k) return 0.0;
  const std::vector<int> lx = levels(x), ly = levels(y);
  if (lx.empty() || lx != ly) return 0.0;
  const int last = lx.back();
  for (int i = 0; i <= k; ++i)
    if ((i < last || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  for (int i = last + 1; i < k; ++i)
    if (is_dirac_surface(x.v[i]) && transmits_from_camera_side(x, i) != transmits_from_camera_side(y, i)) return 0.0;
  const auto rx = path_raster(*ctx_, x), ry = path_raster(*ctx_, y);
  if (!rx || !ry) return 0.0;
  double t = lens_.kernel_density(*ry - *rx) * static_cast<double>(ctx_->world->camera().pixel_count()) *
             pdf_next(*ctx_, nullptr, y.v[k], y.v[k - 1], TransportMode::kRadiance);
  // Every vertex below y_{k-1} down to y_last: after a specular vertex the kept-lobe pseudo density,
  // after a continued non-specular level the angular kernel converted to area.
  for (int i = k - 1; i > last; --i) {
    if (is_dirac_surface(y.v[i])) {
      t *= pdf_next_dirac(*ctx_, &y.v[i + 1], y.v[i], y.v[i - 1], TransportMode::kRadiance, DiracLobeChoice::kKept);
      continue;
    }
    const Vec3 wx = apex_direction(x, i), wy = apex_direction(y, i);
    const double theta = std::atan2(glm::length(glm::cross(wx, wy)), glm::dot(wx, wy));
    const Vec3 o = spawn_ray(y.v[i].hit, direction(y.v[i], y.v[i - 1])).o;
    t *= angular_density(theta) * solid_angle_to_area(1.0, o, y.v[i - 1].hit.p, y.v[i - 1].geometric_normal());
  }
  return t;
}

}  // namespace tb::path_space

#include "lib/mcmc/path_space/caustic_perturbation.h"

#include <cmath>

#include "lib/core/frame.h"
#include "lib/geometry/spawn.h"
#include "lib/path/measure.h"

namespace tb::path_space {

bool CausticPerturbation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 2 || x.v[k].kind != VertexKind::kCamera) return false;
  const PathVertex& a = x.v[k - 2];
  const PathVertex& b = x.v[k - 1];
  if (a.infinite || a.delta || !b.is_surface() || b.delta) return false;
  if (k == 2) return a.light != nullptr;  // emission from x_0
  return a.is_surface() && a.bsdf != nullptr;
}

double CausticPerturbation::kernel_density(double theta) const {
  if (!(theta >= theta1_) || !(theta <= theta2_)) return 0.0;
  return 1.0 / (2.0 * kPi * std::sin(theta) * theta * std::log(theta2_ / theta1_));
}

Vec3 CausticPerturbation::apex(const MltPath& x) const {
  const int k = x.segments();
  // spawn_ray leaves surfaces and area-emitter points robustly; a point light has no offset.
  return spawn_ray(x.v[k - 2].hit, direction(x.v[k - 2], x.v[k - 1])).o;
}

bool CausticPerturbation::same_side(const MltPath& x, const Vec3& p) const {
  const int k = x.segments();
  const PathVertex& a = x.v[k - 2];
  const Vec3 ng = a.geometric_normal();
  return glm::dot(ng, x.v[k - 1].hit.p - a.hit.p) * glm::dot(ng, p - a.hit.p) > 0.0 ||
         (ng.x == 0 && ng.y == 0 && ng.z == 0);
}

std::optional<MltPath> CausticPerturbation::perturb(const MltPath& x, double theta, double phi) const {
  if (!applicable(x)) return std::nullopt;
  const int k = x.segments();
  const Vec3 o = apex(x);
  const Frame fr = Frame::from_z(glm::normalize(x.v[k - 1].hit.p - o));
  const double st = std::sin(theta);
  const Vec3 w = glm::normalize(fr.to_world(Vec3(st * std::cos(phi), st * std::sin(phi), std::cos(theta))));
  if (!same_side(x, x.v[k - 2].hit.p + w)) return std::nullopt;  // through the surface at x_{k-2}
  const auto hit = ctx_->world->geometry().intersect(Ray{o, w});
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

std::optional<MltPath> CausticPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 uo = u.next2();
  const double theta = theta2_ * std::exp(-std::log(theta2_ / theta1_) * uo.x);
  return perturb(x, theta, 2.0 * kPi * uo.y);
}

double CausticPerturbation::angle(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  const Vec3 o = apex(x);
  const Vec3 a = glm::normalize(x.v[k - 1].hit.p - o), b = glm::normalize(y.v[k - 1].hit.p - o);
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

double CausticPerturbation::area_factor(const MltPath& x) const {
  const int k = x.segments();
  return solid_angle_to_area(1.0, apex(x), x.v[k - 1].hit.p, x.v[k - 1].geometric_normal());
}

double CausticPerturbation::density(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return 0.0;
  for (int i = 0; i <= k; ++i)
    if (i != k - 1 && !same_vertex(x.v[i], y.v[i])) return 0.0;
  if (!same_side(x, y.v[k - 1].hit.p)) return 0.0;
  return kernel_density(angle(x, y)) * area_factor(y);
}

}  // namespace tb::path_space

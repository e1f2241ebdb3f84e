#include "lib/mcmc/path_space/caustic_perturbation.h"

#include <cmath>

#include "lib/core/frame.h"
#include "lib/geometry/spawn.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"

namespace tb::path_space {

int CausticPerturbation::chain_start(const MltPath& x) const {
  int j = x.segments() - 2;
  while (j >= 0 && is_dirac_surface(x.v[j])) --j;
  return j;
}

bool CausticPerturbation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 2 || x.v[k].kind != VertexKind::kCamera) return false;
  const int j = chain_start(x);
  if (j < 0) return false;
  const PathVertex& a = x.v[j];
  const PathVertex& b = x.v[k - 1];
  if (a.infinite || a.delta || !b.is_surface() || is_dirac_surface(b)) return false;
  if (j == 0) return a.light != nullptr;  // emission from x_0
  return a.is_surface() && a.bsdf != nullptr;
}

double CausticPerturbation::kernel_density(double theta) const {
  if (!(theta >= theta1_) || !(theta <= theta2_)) return 0.0;
  return 1.0 / (2.0 * kPi * std::sin(theta) * theta * std::log(theta2_ / theta1_));
}

Vec3 CausticPerturbation::apex(const MltPath& x) const {
  const int j = chain_start(x);
  // spawn_ray leaves surfaces and area-emitter points robustly; a point light has no offset.
  return spawn_ray(x.v[j].hit, direction(x.v[j], x.v[j + 1])).o;
}

bool CausticPerturbation::same_side(const MltPath& x, const Vec3& p) const {
  const int j = chain_start(x);
  const PathVertex& a = x.v[j];
  const Vec3 ng = a.geometric_normal();
  return glm::dot(ng, x.v[j + 1].hit.p - a.hit.p) * glm::dot(ng, p - a.hit.p) > 0.0 ||
         (ng.x == 0 && ng.y == 0 && ng.z == 0);
}

std::optional<MltPath> CausticPerturbation::perturb(const MltPath& x, double theta, double phi) const {
  if (!applicable(x)) return std::nullopt;
  const int k = x.segments(), j = chain_start(x);
  const Vec3 o = apex(x);
  const Frame fr = Frame::from_z(glm::normalize(x.v[j + 1].hit.p - o));
  const double st = std::sin(theta);
  const Vec3 w = glm::normalize(fr.to_world(Vec3(st * std::cos(phi), st * std::sin(phi), std::cos(theta))));
  if (!same_side(x, x.v[j].hit.p + w)) return std::nullopt;  // through the surface at x_j
  const auto hit = ctx_->world->geometry().intersect(Ray{o, w});
  if (!hit) return std::nullopt;
  MltPath y = x;
  y.v[j + 1] = surface_vertex(*ctx_, *hit);
  // Through the specular chain, each vertex with its lobe in x (Veach 1997, Sec. 11.4.4).
  for (int i = j + 1; i <= k - 2; ++i) {
    if (!is_dirac_surface(y.v[i])) return std::nullopt;
    const auto s =
        dirac_lobe_sample(y.v[i], direction(y.v[i], y.v[i - 1]), transmits_from_light_side(x, i), TransportMode::kImportance);
    if (!s) return std::nullopt;
    const auto h = ctx_->world->geometry().intersect(spawn_ray(y.v[i].hit, s->wi));
    if (!h) return std::nullopt;
    y.v[i + 1] = surface_vertex(*ctx_, *h);
  }
  if (is_dirac_surface(y.v[k - 1])) return std::nullopt;
  return y;
}

std::optional<MltPath> CausticPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 uo = u.next2();
  const double theta = theta2_ * std::exp(-std::log(theta2_ / theta1_) * uo.x);
  return perturb(x, theta, 2.0 * kPi * uo.y);
}

double CausticPerturbation::angle(const MltPath& x, const MltPath& y) const {
  const int i = perturbed_index(x);
  const Vec3 o = apex(x);
  const Vec3 a = glm::normalize(x.v[i].hit.p - o), b = glm::normalize(y.v[i].hit.p - o);
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

double CausticPerturbation::area_factor(const MltPath& x) const {
  const int k = x.segments(), j = chain_start(x);
  double g = solid_angle_to_area(1.0, apex(x), x.v[j + 1].hit.p, x.v[j + 1].geometric_normal());
  for (int i = j + 1; i <= k - 2; ++i)
    g *= pdf_next_dirac(*ctx_, &x.v[i - 1], x.v[i], x.v[i + 1], TransportMode::kImportance, DiracLobeChoice::kKept);
  return g;
}

double CausticPerturbation::density(const MltPath& x, const MltPath& y) const {
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return 0.0;
  const int j = chain_start(x);
  if (chain_start(y) != j) return 0.0;
  for (int i = 0; i <= k; ++i)
    if ((i <= j || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  for (int i = j + 1; i <= k - 2; ++i)
    if (transmits_from_light_side(x, i) != transmits_from_light_side(y, i)) return 0.0;
  if (!same_side(x, y.v[j + 1].hit.p)) return 0.0;
  return kernel_density(angle(x, y)) * area_factor(y);
}

}  // namespace tb::path_space

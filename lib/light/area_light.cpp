#include "lib/light/area_light.h"

namespace tb {

AreaLight::AreaLight(const Scene& scene, uint32_t shape_id, const Rgb& radiance, bool two_sided)
    : scene_(&scene), shape_id_(shape_id), radiance_(radiance), two_sided_(two_sided),
      mesh_(scene.is_mesh(shape_id) ? &scene.mesh(shape_id) : nullptr) {
  // A = E[1 / pdf_A(x)] for x drawn from the area sampler (exact when pdf_A is constant).
  constexpr int kN = 64;
  CompensatedSum sum;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const AreaSample s = scene.sample_area(shape_id, Vec2((i + 0.5) / kN, (j + 0.5) / kN));
      if (s.pdf_area > 0) sum += 1.0 / s.pdf_area;
    }
  area_ = sum.value() / (kN * kN);
}

Rgb AreaLight::le(const Vec3& n, const Vec3& w) const {
  if (two_sided_ || glm::dot(n, w) > 0) return radiance_;
  return Rgb(0.0);
}

double AreaLight::pdf_area(const SurfacePoint& h) const { return scene_->pdf_area(h); }

std::optional<LightLiPoint> AreaLight::li_from(const Vec3& ref, const Vec3& p, const Vec3& n, double pdf_area) const {
  const Vec3 d = p - ref;
  const double dist2 = glm::dot(d, d);
  const double dist = std::sqrt(dist2);
  const Vec3 wi = d * (1.0 / dist);  // one division instead of three (within an ulp of d / dist)
  // Area -> solid angle at ref (Veach 1997, Eq. 8.10; lib/path/measure.h): pdf_A dist^2 / |cos_light|
  // with |cos_light| = |n.d| / dist, written
  // pdf_A dist^3 / |n.d| so that this division waits only for the square root, not for 1 / dist
  // (the two divisions overlap: this chain precedes every shadow ray).
  const double n_dot_d = std::abs(glm::dot(n, d));
  if (!(pdf_area > 0) || !(dist2 > 0) || !(n_dot_d > 0)) return std::nullopt;
  // A prvalue built in place from every field: no zero-filled record, no copy.
  return std::optional<LightLiPoint>(std::in_place, wi, le(n, -wi), pdf_area * dist2 * dist / n_dot_d, p, n, dist,
                                     pdf_area);
}

std::optional<LightLiSample> AreaLight::sample_li(const Vec3& ref, const Vec2& u) const {
  // Built in place and returned by name on every path (named return value optimisation): the
  // sample carries a full Hit (~220 bytes), whose copies showed in profiles.
  std::optional<LightLiSample> out(std::in_place);
  LightLiSample& ls = *out;
  const double pdf_area = scene_->sample_area_into(shape_id_, u, &ls.hit);
  if (const auto p = li_from(ref, ls.hit.p, ls.hit.n, pdf_area))
    static_cast<LightLiPoint&>(ls) = *p;
  else
    out.reset();
  return out;
}

std::optional<LightLiPoint> AreaLight::sample_li_point(const Vec3& ref, const Vec2& u) const {
  // The point only: no derivatives are computed. Meshes: the p and n Scene::sample_point would
  // give (TriangleMesh::sample_position), with its density 1 / area.
  if (mesh_) {
    const TriangleMesh::PositionNormal at = mesh_->sample_position(u);
    return li_from(ref, at.p, at.n, mesh_->pdf_area());
  }
  double pdf_area = 0.0;
  const SurfacePoint at = scene_->sample_point(shape_id_, u, &pdf_area);
  return li_from(ref, at.p, at.n, pdf_area);
}

double AreaLight::pdf_li(const Vec3& ref, const Vec3& wi, const SurfacePoint* on_light) const {
  if (!on_light || on_light->shape_id != shape_id_) return 0.0;
  const Vec3 d = on_light->p - ref;
  const double dist2 = glm::dot(d, d);
  const double cos_light = std::abs(glm::dot(on_light->n, wi));
  if (!(cos_light > 0) || !(dist2 > 0)) return 0.0;
  return pdf_area(*on_light) * dist2 / cos_light;
}

std::optional<LightLeSample> AreaLight::sample_le(const Vec2& u_pos, const Vec2& u_dir) const {
  // Built in place and returned by name, the point written straight into the sample's Hit
  // (Scene::sample_area_into, the expressions of Scene::sample_area), as in sample_li: no copies of
  // the ~220-byte Hit through an AreaSample and the returned optional.
  std::optional<LightLeSample> out(std::in_place);
  LightLeSample& e = *out;
  const double pdf_area = scene_->sample_area_into(shape_id_, u_pos, &e.hit);
  if (!(pdf_area > 0)) {
    out.reset();
    return out;
  }
  const Vec3 w = sample_emission_direction(e.hit.n, two_sided_, u_dir);
  const double pdf_dir = pdf_emission_direction(e.hit.n, two_sided_, w);
  if (!(pdf_dir > 0)) {
    out.reset();
    return out;
  }
  e.ray = Ray{e.hit.p, w};
  e.n = e.hit.n;
  e.le = le(e.hit.n, w);
  e.pdf_pos = pdf_area;
  e.pdf_dir = pdf_dir;
  return out;
}

void AreaLight::pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const {
  *pdf_pos = pdf_area(at);
  *pdf_dir = pdf_emission_direction(at.n, two_sided_, w);
}

Rgb AreaLight::power() const { return radiance_ * (kPi * area_ * (two_sided_ ? 2.0 : 1.0)); }

}  // namespace tb

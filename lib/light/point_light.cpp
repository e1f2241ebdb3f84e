#include "lib/light/point_light.h"

#include "lib/core/warp_sphere.h"

namespace tb {

std::optional<LightLiSample> PointLight::sample_li(const Vec3& ref, const Vec2&) const {
  const Vec3 d = p_ - ref;
  const double dist2 = glm::dot(d, d);
  if (!(dist2 > 0)) return std::nullopt;
  LightLiSample s;
  s.distance = std::sqrt(dist2);
  s.wi = d / s.distance;
  s.li = intensity_ / dist2;  // I / d^2: irradiance on a surface facing the light, per unit cos
  s.pdf = 1.0;                // delta
  s.p_light = p_;
  s.hit.p = s.p_light;
  s.hit.n = s.hit.ng = s.n_light;
  return s;
}

std::optional<LightLeSample> PointLight::sample_le(const Vec2&, const Vec2& u_dir) const {
  LightLeSample e;
  e.ray = Ray{p_, sample_uniform_sphere(u_dir)};
  e.le = intensity_;
  e.pdf_pos = 1.0;
  e.pdf_dir = pdf_uniform_sphere();
  e.hit.p = e.ray.o;
  e.hit.n = e.hit.ng = e.n;
  return e;
}

void PointLight::pdf_le(const Hit&, const Vec3&, double* pdf_pos, double* pdf_dir) const {
  *pdf_pos = 0.0;  // a delta in position is never reached by chance
  *pdf_dir = pdf_uniform_sphere();
}

SpotLight::SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, double total_width_deg,
                     double falloff_start_deg)
    : p_(position), frame_(Frame::from_z(glm::normalize(direction))), intensity_(intensity),
      cos_total_(std::cos(total_width_deg * kPi / 180.0)),
      cos_start_(std::cos(std::min(falloff_start_deg, total_width_deg) * kPi / 180.0)) {}

Rgb SpotLight::intensity(const Vec3& w) const {
  const double c = glm::dot(w, frame_.n);
  if (c <= cos_total_) return Rgb(0.0);
  if (c >= cos_start_) return intensity_;
  const double t = (c - cos_total_) / (cos_start_ - cos_total_);
  return intensity_ * (t * t * (3.0 - 2.0 * t));  // smoothstep
}

std::optional<LightLiSample> SpotLight::sample_li(const Vec3& ref, const Vec2&) const {
  const Vec3 d = p_ - ref;
  const double dist2 = glm::dot(d, d);
  if (!(dist2 > 0)) return std::nullopt;
  LightLiSample s;
  s.distance = std::sqrt(dist2);
  s.wi = d / s.distance;
  s.li = intensity(-s.wi) / dist2;
  if (is_black(s.li)) return std::nullopt;
  s.pdf = 1.0;
  s.p_light = p_;
  s.hit.p = s.p_light;
  s.hit.n = s.hit.ng = s.n_light;
  return s;
}

std::optional<LightLeSample> SpotLight::sample_le(const Vec2&, const Vec2& u_dir) const {
  const Vec3 local = sample_uniform_cone(u_dir, cos_total_);
  LightLeSample e;
  e.ray = Ray{p_, frame_.to_world(local)};
  e.le = intensity(e.ray.d);
  e.pdf_pos = 1.0;
  e.pdf_dir = pdf_uniform_cone(local, cos_total_);
  e.hit.p = e.ray.o;
  e.hit.n = e.hit.ng = e.n;
  return e;
}

void SpotLight::pdf_le(const Hit&, const Vec3& w, double* pdf_pos, double* pdf_dir) const {
  *pdf_pos = 0.0;
  *pdf_dir = pdf_uniform_cone(frame_.to_local(w), cos_total_);
}

Rgb SpotLight::power() const {
  // 2 pi I [ (1 - cos_start) + (cos_start - cos_total) / 2 ]: the smoothstep integrates to 1/2.
  return intensity_ * (2.0 * kPi * ((1.0 - cos_start_) + 0.5 * (cos_start_ - cos_total_)));
}

}  // namespace tb

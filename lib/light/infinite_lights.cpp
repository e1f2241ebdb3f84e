#include "lib/light/infinite_lights.h"

#include "lib/core/warp_disk.h"
#include "lib/core/warp_sphere.h"

namespace tb {

namespace {
// A point of the disk of radius R centred at c + R (-w), perpendicular to w: where rays
// travelling along w enter the scene sphere.
Vec3 disk_point(const SceneSphere& s, const Vec3& w, const Vec2& u) {
  const Frame f = Frame::from_z(w);
  const Vec2 d = sample_uniform_disk_concentric(u) * s.radius;
  return s.center - s.radius * w + f.s * d.x + f.t * d.y;
}
}  // namespace

DirectionalLight::DirectionalLight(const Vec3& direction, const Rgb& irradiance)
    : w_(glm::normalize(direction)), irradiance_(irradiance) {}

std::optional<LightLiSample> DirectionalLight::sample_li(const Vec3& ref, const Vec2&) const {
  LightLiSample s;
  s.wi = -w_;
  s.li = irradiance_;
  s.pdf = 1.0;
  s.distance = 2.0 * sphere_.radius + glm::length(ref - sphere_.center);
  s.p_light = ref + s.wi * s.distance;
  s.hit.p = s.p_light;
  s.hit.n = s.hit.ng = s.n_light;
  return s;
}

std::optional<LightLeSample> DirectionalLight::sample_le(const Vec2& u_pos, const Vec2&) const {
  LightLeSample e;
  e.ray = Ray{disk_point(sphere_, w_, u_pos), w_};
  e.le = irradiance_;
  e.pdf_pos = 1.0 / (kPi * sphere_.radius * sphere_.radius);
  e.pdf_dir = 1.0;
  e.hit.p = e.ray.o;
  e.hit.n = e.hit.ng = e.n;
  return e;
}

void DirectionalLight::pdf_le(const Hit&, const Vec3&, double* pdf_pos, double* pdf_dir) const {
  *pdf_pos = 1.0 / (kPi * sphere_.radius * sphere_.radius);
  *pdf_dir = 0.0;  // a delta in direction is never reached by chance
}

std::optional<LightLiSample> ConstantEnvironmentLight::sample_li(const Vec3& ref, const Vec2& u) const {
  LightLiSample s;
  s.wi = sample_uniform_sphere(u);
  s.li = radiance_;
  s.pdf = pdf_uniform_sphere();
  s.distance = kInfinity;
  s.p_light = ref + s.wi * (2.0 * sphere_.radius + glm::length(ref - sphere_.center));
  s.hit.p = s.p_light;
  s.hit.n = s.hit.ng = s.n_light;
  return s;
}

double ConstantEnvironmentLight::pdf_li(const Vec3&, const Vec3&, const SurfacePoint* on_light) const {
  return on_light ? 0.0 : pdf_uniform_sphere();
}

std::optional<LightLeSample> ConstantEnvironmentLight::sample_le(const Vec2& u_pos, const Vec2& u_dir) const {
  const Vec3 w = -sample_uniform_sphere(u_dir);  // direction of travel into the scene
  LightLeSample e;
  e.ray = Ray{disk_point(sphere_, w, u_pos), w};
  e.le = radiance_;
  e.pdf_pos = 1.0 / (kPi * sphere_.radius * sphere_.radius);
  e.pdf_dir = pdf_uniform_sphere();
  e.hit.p = e.ray.o;
  e.hit.n = e.hit.ng = e.n;
  return e;
}

void ConstantEnvironmentLight::pdf_le(const Hit&, const Vec3&, double* pdf_pos, double* pdf_dir) const {
  *pdf_pos = 1.0 / (kPi * sphere_.radius * sphere_.radius);
  *pdf_dir = pdf_uniform_sphere();
}

}  // namespace tb

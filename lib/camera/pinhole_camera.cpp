#include "lib/camera/pinhole_camera.h"

namespace tb {

Vec3 PinholeCamera::direction_through(const Vec2& raster) const {
  const Vec2 p = proj_.plane_from_raster(raster);
  return glm::normalize(proj_.to_world_dir(Vec3(p.x, p.y, 1.0)));
}

CameraRay PinholeCamera::generate_ray(const Vec2& raster, const Vec2& /*lens_u*/) const {
  CameraRay out;
  RayDifferential& r = out.ray;
  r.o = proj_.eye();
  r.d = direction_through(raster);
  // Igehy 1999: offset rays one pixel over in x and in y.
  r.has_differentials = true;
  r.rx_o = r.o;
  r.ry_o = r.o;
  r.rx_d = direction_through(raster + Vec2(1.0, 0.0));
  r.ry_d = direction_through(raster + Vec2(0.0, 1.0));
  return out;
}

CameraPrimaryRay PinholeCamera::generate_primary_ray(const Vec2& raster, const Vec2& /*lens_u*/) const {
  return {Ray{proj_.eye(), direction_through(raster)}, 1.0};
}

std::optional<CameraRasterHit> PinholeCamera::raster_from_ray(const Ray& ray) const {
  const Vec3 d = proj_.to_camera_dir(ray.d);
  if (!(d.z > 0.0) || !is_finite(d)) return std::nullopt;
  const Vec2 raster = proj_.raster_from_plane({d.x / d.z, d.y / d.z});
  if (!proj_.inside(raster)) return std::nullopt;
  return CameraRasterHit{raster, Vec2(0.5), proj_.eye()};
}

double PinholeCamera::importance(const Ray& ray) const {
  if (!raster_from_ray(ray)) return 0.0;
  return importance_inside(ray);
}

double PinholeCamera::importance_inside(const Ray& ray) const {
  const double cos_t = proj_.to_camera_dir(ray.d).z / glm::length(ray.d);
  // pbrt-v3 Eq. 16.3 with A_lens = 1: We = 1 / (A cos^4 theta).
  return 1.0 / (proj_.plane_area() * sqr(sqr(cos_t)));
}

CameraPdf PinholeCamera::pdf_we(const Ray& ray) const {
  CameraPdf pdf;
  pdf.pos_is_delta = true;
  pdf.pos = 1.0;
  if (!raster_from_ray(ray)) return pdf;
  const double cos_t = proj_.to_camera_dir(ray.d).z / glm::length(ray.d);
  // Uniform raster density 1/P times dA_raster/dw = (P / A) / cos^3 theta.
  pdf.dir = 1.0 / (proj_.plane_area() * cos_t * cos_t * cos_t);
  return pdf;
}

std::optional<CameraWiSample> PinholeCamera::sample_wi(const Vec3& ref, const Vec2& /*lens_u*/) const {
  CameraWiSample s;
  s.lens_point = proj_.eye();
  const Vec3 to_eye = s.lens_point - ref;
  s.distance = glm::length(to_eye);
  if (!(s.distance > 0.0)) return std::nullopt;
  s.wi = to_eye / s.distance;
  const Ray out{s.lens_point, -s.wi};
  const auto hit = raster_from_ray(out);
  if (!hit) return std::nullopt;
  s.raster = hit->raster;
  s.importance = importance_inside(out);  // importance(out), its raster mapping done just above
  // The Dirac lens position carries unit mass: pdf = dist^2 / cos theta (pbrt-v3 Sample_Wi
  // with lensArea = 1), so We cos / pdf reproduces the geometry term We cos cos' / dist^2
  // once the caller multiplies by the cosine at the reference point.
  const double cos_lens = glm::dot(proj_.forward(), -s.wi);
  s.pdf = s.distance * s.distance / cos_lens;
  s.delta = true;
  return s;
}

}  // namespace tb

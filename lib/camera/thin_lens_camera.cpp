#include "lib/camera/thin_lens_camera.h"

#include <stdexcept>

#include <fmt/format.h>

#include "lib/core/warp_disk.h"

namespace tb {

ThinLensCamera::ThinLensCamera(const CameraSetup& setup)
    : Camera(setup), radius_(setup.lens_radius), focus_(setup.focus_distance) {
  if (!(radius_ > 0.0)) throw std::invalid_argument(fmt::format("thin_lens: lens radius {} <= 0", radius_));
  if (!(focus_ > 0.0)) throw std::invalid_argument(fmt::format("thin_lens: focus distance {} <= 0", focus_));
}

Vec3 ThinLensCamera::lens_point_camera(const Vec2& lens_u) const {
  const Vec2 d = sample_uniform_disk_concentric(lens_u);
  return {radius_ * d.x, radius_ * d.y, 0.0};
}

Vec2 ThinLensCamera::lens_uniforms(const Vec3& lens_point_camera) const {
  return invert_uniform_disk_concentric(Vec2(lens_point_camera.x, lens_point_camera.y) / radius_);
}

double ThinLensCamera::pdf_lens_area(const Vec2& lens_xy) const {
  return glm::dot(lens_xy, lens_xy) <= radius_ * radius_ ? 1.0 / lens_area() : 0.0;
}

Vec3 ThinLensCamera::focus_point_camera(const Vec2& raster) const {
  const Vec2 p = proj_.plane_from_raster(raster);
  return focus_ * Vec3(p.x, p.y, 1.0);
}

CameraRay ThinLensCamera::generate_ray(const Vec2& raster, const Vec2& lens_u) const {
  const Vec3 lens = lens_point_camera(lens_u);
  CameraRay out;
  RayDifferential& r = out.ray;
  r.o = proj_.to_world_point(lens);
  r.d = glm::normalize(proj_.to_world_dir(focus_point_camera(raster) - lens));
  // Igehy 1999: same lens point, focus points of the raster positions one pixel over.
  r.has_differentials = true;
  r.rx_o = r.o;
  r.ry_o = r.o;
  r.rx_d = glm::normalize(proj_.to_world_dir(focus_point_camera(raster + Vec2(1.0, 0.0)) - lens));
  r.ry_d = glm::normalize(proj_.to_world_dir(focus_point_camera(raster + Vec2(0.0, 1.0)) - lens));
  return out;
}

CameraPrimaryRay ThinLensCamera::generate_primary_ray(const Vec2& raster, const Vec2& lens_u) const {
  const Vec3 lens = lens_point_camera(lens_u);
  return {Ray{proj_.to_world_point(lens), glm::normalize(proj_.to_world_dir(focus_point_camera(raster) - lens))}, 1.0};
}

std::optional<CameraRasterHit> ThinLensCamera::raster_from_ray(const Ray& ray) const {
  const Vec3 o = proj_.to_camera_point(ray.o);
  const Vec3 d = proj_.to_camera_dir(ray.d);
  if (!(d.z > 0.0) || !is_finite(d) || !is_finite(o)) return std::nullopt;
  // Where the ray's line crosses the lens plane z = 0 (o itself for rays started on the lens).
  const Vec3 lens = o.z == 0.0 ? o : o - d * (o.z / d.z);
  if (lens.x * lens.x + lens.y * lens.y > radius_ * radius_) return std::nullopt;
  // Point in focus, then the image-plane point on the chief ray through it.
  const Vec3 focus = lens + d * (focus_ / d.z);
  const Vec2 raster = proj_.raster_from_plane({focus.x / focus_, focus.y / focus_});
  if (!proj_.inside(raster)) return std::nullopt;
  return CameraRasterHit{raster, lens_uniforms(Vec3(lens.x, lens.y, 0.0)),
                         proj_.to_world_point(Vec3(lens.x, lens.y, 0.0))};
}

double ThinLensCamera::importance(const Ray& ray) const {
  if (!raster_from_ray(ray)) return 0.0;
  const double cos_t = proj_.to_camera_dir(ray.d).z / glm::length(ray.d);
  // pbrt-v3 Eq. 16.3: We = 1 / (A_plane A_lens cos^4 theta).
  return 1.0 / (proj_.plane_area() * lens_area() * sqr(sqr(cos_t)));
}

CameraPdf ThinLensCamera::pdf_we(const Ray& ray) const {
  CameraPdf pdf;
  if (!raster_from_ray(ray)) return pdf;
  const double cos_t = proj_.to_camera_dir(ray.d).z / glm::length(ray.d);
  pdf.pos = 1.0 / lens_area();
  pdf.dir = 1.0 / (proj_.plane_area() * cos_t * cos_t * cos_t);
  return pdf;
}

std::optional<CameraWiSample> ThinLensCamera::sample_wi(const Vec3& ref, const Vec2& lens_u) const {
  CameraWiSample s;
  s.lens_point = proj_.to_world_point(lens_point_camera(lens_u));
  const Vec3 to_lens = s.lens_point - ref;
  s.distance = glm::length(to_lens);
  if (!(s.distance > 0.0)) return std::nullopt;
  s.wi = to_lens / s.distance;
  const Ray out{s.lens_point, -s.wi};
  const auto hit = raster_from_ray(out);
  if (!hit) return std::nullopt;
  s.raster = hit->raster;
  s.importance = importance(out);
  // Area density 1 / A_lens converted to solid angle at ref: dist^2 / (cos_lens A_lens).
  const double cos_lens = glm::dot(proj_.forward(), -s.wi);
  s.pdf = s.distance * s.distance / (cos_lens * lens_area());
  return s;
}

}  // namespace tb

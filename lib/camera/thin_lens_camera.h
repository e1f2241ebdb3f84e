// Thin-lens camera (Kolb et al. 1995; pbrt-v3 Sec. 6.2.3): a disk lens of radius r in the
// plane z = 0 of camera space, sampled uniformly by the concentric map (lib/core/warp_disk.h),
// focused at distance d_f. The ray from lens point p passes through the point where the ray
// from the lens centre through the raster position meets the plane z = d_f.
// We = 1 / (A_plane pi r^2 cos^4 theta), pdf_pos = 1 / (pi r^2) (area), pdf_dir =
// 1 / (A_plane cos^3 theta) (solid angle) (pbrt-v3 Sec. 16.1.1).
#pragma once

#include "lib/camera/camera.h"

namespace tb {

class ThinLensCamera final : public Camera {
 public:
  // Throws std::invalid_argument unless lens_radius > 0 and focus_distance > 0.
  explicit ThinLensCamera(const CameraSetup& setup);

  std::string_view name() const override { return "thin_lens"; }
  double lens_radius() const { return radius_; }
  double focus_distance() const { return focus_; }
  double lens_area() const override { return kPi * radius_ * radius_; }
  bool lens_is_delta() const override { return false; }

  // Lens uniforms -> lens point in camera space (z = 0), and back (concentric map inverse).
  Vec3 lens_point_camera(const Vec2& lens_u) const;
  Vec2 lens_uniforms(const Vec3& lens_point_camera) const;
  // Area density of lens points (camera or world units; rigid frame): 1 / (pi r^2) on the disk.
  double pdf_lens_area(const Vec2& lens_xy) const;

  CameraRay generate_ray(const Vec2& raster, const Vec2& lens_u) const override;
  CameraPrimaryRay generate_primary_ray(const Vec2& raster, const Vec2& lens_u) const override;
  std::optional<CameraRasterHit> raster_from_ray(const Ray& ray) const override;
  double importance(const Ray& ray) const override;
  CameraPdf pdf_we(const Ray& ray) const override;
  std::optional<CameraWiSample> sample_wi(const Vec3& ref, const Vec2& lens_u) const override;

 private:
  Vec3 focus_point_camera(const Vec2& raster) const;
  double radius_, focus_;
};

}  // namespace tb

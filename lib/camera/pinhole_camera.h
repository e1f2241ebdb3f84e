// Pinhole camera: every ray starts at the eye; the lens position is a Dirac delta (pdf_pos = 1
// by convention, flagged). We = 1 / (A_plane cos^4 theta) (pbrt-v3 Sec. 16.1.1 with lens area 1).
#pragma once

#include "lib/camera/camera.h"

namespace tb {

class PinholeCamera final : public Camera {
 public:
  explicit PinholeCamera(const CameraSetup& setup) : Camera(setup) {}

  std::string_view name() const override { return "pinhole"; }
  double lens_area() const override { return 1.0; }
  bool lens_is_delta() const override { return true; }
  CameraRay generate_ray(const Vec2& raster, const Vec2& lens_u) const override;
  CameraPrimaryRay generate_primary_ray(const Vec2& raster, const Vec2& lens_u) const override;
  std::optional<CameraRasterHit> raster_from_ray(const Ray& ray) const override;
  double importance(const Ray& ray) const override;
  CameraPdf pdf_we(const Ray& ray) const override;
  double pdf_we_pos(const Ray&) const override { return 1.0; }  // pdf_we's pos for every ray
  std::optional<CameraWiSample> sample_wi(const Vec3& ref, const Vec2& lens_u) const override;

 private:
  Vec3 direction_through(const Vec2& raster) const;
  // importance(ray) for a ray known to pass through the image (raster_from_ray succeeded).
  double importance_inside(const Ray& ray) const;
};

}  // namespace tb

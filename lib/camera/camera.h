// The camera interface in the conventions a bidirectional path tracer needs (Veach 1997,
// Sec. 10.2 and 8.1 "importance"; pbrt-v3 Sec. 16.1.1 PerspectiveCamera::We / Pdf_We /
// Sample_Wi). docs/camera.md derives the normalisation; in short, for a film of P = W H pixels
// of unit raster area and a lens of area A_lens (Dirac for the pinhole):
//
//   We(p, w) = 1 / (A_plane A_lens cos^4 theta)  for rays through the image, 0 otherwise,
//   so that  int_lens int_image We(p, w) cos theta dw dA(p) = 1       (whole image),
//   and the measurement of pixel j is  I_j = int int W_e^(j) L cos dw dA  with
//   W_e^(j)(p, w) = P h_j(raster(p, w)) We(p, w), h_j the pixel's filter (unit raster integral).
//
// Densities: pdf_pos w.r.t. area on the lens (a Dirac mass of 1 for the pinhole, flagged),
// pdf_dir w.r.t. solid angle at the lens point, pdf of sample_wi w.r.t. solid angle at the
// reference point. theta is the angle between the ray and the camera's forward axis.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "lib/camera/perspective_projection.h"
#include "lib/core/ray.h"

namespace tb {

// A primary ray. weight = We cos / (pdf_pos pdf_dir pdf_raster-normalisation) = 1 for both
// perspective cameras when the raster position is sampled uniformly within a pixel.
struct CameraRay {
  RayDifferential ray;  // unit direction, origin on the lens
  double weight = 1.0;
};

// A primary ray without differentials (Camera::generate_primary_ray); weight as in CameraRay.
struct CameraPrimaryRay {
  Ray ray;
  double weight = 1.0;
};

// Where a ray leaving the camera meets the film, and where it crosses the lens.
struct CameraRasterHit {
  Vec2 raster{0.0};
  Vec2 lens_uniforms{0.5};  // the uniforms that generate the lens point ((0.5, 0.5) for a pinhole)
  Vec3 lens_point{0.0};     // world space
};

struct CameraPdf {
  double pos = 0.0;          // area measure on the lens; 1 for a Dirac lens (pos_is_delta)
  double dir = 0.0;          // solid angle at the lens point
  bool pos_is_delta = false;
};

// A connection from a scene point to the camera, for light tracing (pbrt-v3 Sample_Wi).
struct CameraWiSample {
  Vec3 wi{0.0};              // unit, from the reference point towards the lens point
  double distance = 0.0;
  Vec3 lens_point{0.0};
  Vec2 raster{0.0};
  double importance = 0.0;   // We(lens point, -wi), whole-image normalisation
  double pdf = 0.0;          // solid angle at the reference point (Dirac lens: unit mass)
  bool delta = false;        // pinhole: the lens position is a Dirac delta
};

class Camera {
 public:
  explicit Camera(const CameraSetup& setup) : proj_(setup) {}
  virtual ~Camera() = default;

  virtual std::string_view name() const = 0;
  const PerspectiveProjection& projection() const { return proj_; }
  int width() const { return proj_.width(); }
  int height() const { return proj_.height(); }
  int64_t pixel_count() const { return proj_.pixel_count(); }
  // Lens area (1 for the pinhole, whose lens position is a Dirac delta).
  virtual double lens_area() const = 0;
  virtual bool lens_is_delta() const = 0;

  // Primary ray through the raster position, lens point from lens uniforms in [0,1)^2 (ignored
  // by the pinhole). Differentials (Igehy 1999): the rays through raster + (1, 0) and
  // raster + (0, 1) from the same lens point.
  virtual CameraRay generate_ray(const Vec2& raster, const Vec2& lens_u) const = 0;
  // The same primary ray (bit-identical origin, direction and weight) without differentials,
  // for integrators that do not use them: a third of the work, and a smaller record.
  virtual CameraPrimaryRay generate_primary_ray(const Vec2& raster, const Vec2& lens_u) const {
    const CameraRay r = generate_ray(raster, lens_u);
    return {Ray{r.ray.o, r.ray.d}, r.weight};
  }

  // Inverse of generate_ray: the raster position (and lens point) of a ray leaving the camera,
  // or nothing when it does not pass through the image (or misses the lens). The thin lens
  // uses the point where the ray's line crosses the lens plane; the pinhole uses the direction.
  virtual std::optional<CameraRasterHit> raster_from_ray(const Ray& ray) const = 0;
  // The ray from the lens centre (the eye) with this world direction.
  std::optional<CameraRasterHit> raster_from_direction(const Vec3& world_dir) const {
    return raster_from_ray(Ray{proj_.eye(), world_dir});
  }
  // The ray from a world-space lens point to a world point (pinhole: lens_point is the eye).
  std::optional<CameraRasterHit> raster_from_point(const Vec3& world_point, const Vec3& lens_point) const {
    return raster_from_ray(Ray{lens_point, world_point - lens_point});
  }

  // Importance We(ray) of a ray leaving the camera (0 outside the image / off the lens).
  virtual double importance(const Ray& ray) const = 0;
  // Densities of generating this ray by generate_ray with uniform raster and lens uniforms.
  virtual CameraPdf pdf_we(const Ray& ray) const = 0;
  // pdf_we(ray).pos alone, bitwise (the pinhole's is 1 for every ray: no raster mapping needed).
  virtual double pdf_we_pos(const Ray& ray) const { return pdf_we(ray).pos; }
  // Samples a lens point from lens uniforms and connects the reference point to it.
  virtual std::optional<CameraWiSample> sample_wi(const Vec3& ref, const Vec2& lens_u) const = 0;

 protected:
  PerspectiveProjection proj_;
};

// "pinhole" or "thin_lens"; throws std::invalid_argument naming an unknown camera.
std::unique_ptr<Camera> make_camera(std::string_view name, const CameraSetup& setup);

}  // namespace tb

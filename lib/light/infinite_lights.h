// Lights at infinity. Both emit, for light tracing, from a disk of the scene sphere's radius
// perpendicular to the emission direction (pbrt-v3 Sec. 16.1.4 construction).
#pragma once

#include "lib/light/light.h"

namespace tb {

// Parallel light travelling along `direction` with irradiance E on surfaces facing it: a delta
// in direction.
class DirectionalLight final : public Light {
 public:
  DirectionalLight(const Vec3& direction, const Rgb& irradiance);
  std::string_view name() const override { return "directional"; }
  uint32_t flags() const override { return light_flags::kDeltaDirection | light_flags::kInfinite; }
  void set_scene_sphere(const SceneSphere& s) override { sphere_ = s; }

  std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const override;
  double pdf_li(const Vec3&, const Vec3&, const SurfacePoint*) const override { return 0.0; }
  std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const override;
  void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const override;
  Rgb le(const Vec3&, const Vec3&) const override { return Rgb(0.0); }
  Rgb power() const override { return irradiance_ * (kPi * sphere_.radius * sphere_.radius); }

 private:
  Vec3 w_;  // direction of travel (unit)
  Rgb irradiance_;
  SceneSphere sphere_;
};

// Constant radiance L arriving from every direction. sample_li draws directions uniformly on
// the sphere (density 1/(4 pi) in solid angle).
class ConstantEnvironmentLight final : public Light {
 public:
  explicit ConstantEnvironmentLight(const Rgb& radiance) : radiance_(radiance) {}
  std::string_view name() const override { return "environment"; }
  uint32_t flags() const override { return light_flags::kInfinite; }
  void set_scene_sphere(const SceneSphere& s) override { sphere_ = s; }

  std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const override;
  double pdf_li(const Vec3& ref, const Vec3& wi, const SurfacePoint* on_light) const override;
  std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const override;
  void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const override;
  // Radiance arriving along a ray that escapes the scene (any direction).
  Rgb le(const Vec3&, const Vec3&) const override { return radiance_; }
  Rgb power() const override { return radiance_ * (4.0 * kPi * kPi * sphere_.radius * sphere_.radius); }

 private:
  Rgb radiance_;
  SceneSphere sphere_;
};

}  // namespace tb

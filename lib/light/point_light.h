// Isotropic point light of intensity I [W/sr] at a position: a delta in position.
#pragma once

#include "lib/light/light.h"

namespace tb {

class PointLight final : public Light {
 public:
  PointLight(const Vec3& position, const Rgb& intensity) : p_(position), intensity_(intensity) {}
  std::string_view name() const override { return "point"; }
  uint32_t flags() const override { return light_flags::kDeltaPosition; }
  const Vec3& position() const { return p_; }

  std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const override;
  double pdf_li(const Vec3&, const Vec3&, const SurfacePoint*) const override { return 0.0; }
  std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const override;
  void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const override;
  Rgb le(const Vec3&, const Vec3&) const override { return Rgb(0.0); }
  Rgb power() const override { return 4.0 * kPi * intensity_; }

 private:
  Vec3 p_;
  Rgb intensity_;
};

// Spot light: intensity I inside a cone about `direction`, full inside cos_falloff_start,
// smoothstep falloff to zero at cos_total_width (pbrt-v4's spot light profile).
class SpotLight final : public Light {
 public:
  SpotLight(const Vec3& position, const Vec3& direction, const Rgb& intensity, double total_width_deg,
            double falloff_start_deg);
  std::string_view name() const override { return "spot"; }
  uint32_t flags() const override { return light_flags::kDeltaPosition; }

  std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const override;
  double pdf_li(const Vec3&, const Vec3&, const SurfacePoint*) const override { return 0.0; }
  std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const override;
  void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const override;
  Rgb le(const Vec3&, const Vec3&) const override { return Rgb(0.0); }
  Rgb power() const override;
  // Intensity towards world direction w (unit).
  Rgb intensity(const Vec3& w) const;

 private:
  Vec3 p_;
  Frame frame_;
  Rgb intensity_;
  double cos_total_, cos_start_;
};

}  // namespace tb

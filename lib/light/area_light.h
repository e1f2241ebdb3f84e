// Diffuse area emitter on any shape of the scene (triangle mesh or analytic shape): constant
// radiance Le leaving its front side (the side the shading normal points to), or both sides.
// Next-event estimation samples the shape by area (Scene::sample_area) and converts to solid
// angle at the reference point: pdf_w = pdf_A * d^2 / |cos theta_light| (Veach 1997, Eq. 8.10).
#pragma once

#include "lib/geometry/scene.h"
#include "lib/light/light.h"

namespace tb {

class AreaLight final : public Light {
 public:
  // `scene` must outlive the light and be committed before any query.
  AreaLight(const Scene& scene, uint32_t shape_id, const Rgb& radiance, bool two_sided = false);

  std::string_view name() const override { return "area"; }
  uint32_t flags() const override { return light_flags::kArea; }
  uint32_t shape_id() const { return shape_id_; }
  bool two_sided() const { return two_sided_; }
  const Rgb& radiance() const { return radiance_; }

  std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const override;
  std::optional<LightLiPoint> sample_li_point(const Vec3& ref, const Vec2& u) const override;
  double pdf_li(const Vec3& ref, const Vec3& wi, const SurfacePoint* on_light) const override;
  std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const override;
  void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const override;
  Rgb le(const Vec3& n, const Vec3& w) const override;
  Rgb power() const override;

  // Density of sampled points per unit area at a hit on this light.
  double pdf_area(const SurfacePoint& h) const;
  // World-space area of the emitter (exact for shapes sampled uniformly by area; otherwise the
  // importance-sampling estimate E[1/pdf] over 4096 stratified points).
  double area() const { return area_; }

 private:
  // The sample at the emitter point p with shading normal n (area density pdf_area); empty
  // when it is unusable.
  std::optional<LightLiPoint> li_from(const Vec3& ref, const Vec3& p, const Vec3& n, double pdf_area) const;
  const Scene* scene_;
  uint32_t shape_id_;
  Rgb radiance_;
  bool two_sided_;
  // The emitter's mesh when it is a triangle mesh (null for analytic shapes): next-event
  // estimation samples it directly, TriangleMesh::sample_position instead of
  // Scene::sample_point (no shape lookup, no error bound or ids that li_from never reads).
  // Stable: the scene is committed when the light is built, and no shape is added after commit.
  const TriangleMesh* mesh_ = nullptr;
  double area_ = 0.0;
};

}  // namespace tb

// An analytic shape placed in the world by an affine object-to-world transform, optionally
// with its normal flipped. Evaluates world-space differential geometry in double, intersects
// world rays (in object space, double) and samples points by area.
#pragma once

#include <memory>
#include <optional>

#include "lib/geometry/analytic_shape.h"
#include "lib/geometry/area_sample.h"
#include "lib/geometry/hit.h"
#include "lib/geometry/ray.h"
#include "lib/geometry/transform.h"

namespace tb {

class ShapeInstance {
 public:
  ShapeInstance(std::shared_ptr<const AnalyticShape> shape, const AffineTransform& to_world = {},
                bool flip_normal = false);

  const AnalyticShape& shape() const { return *shape_; }
  const AffineTransform& to_world() const { return xf_; }
  bool flip_normal() const { return flip_; }

  // World-space differential geometry at (u, v). Positions and tangents are the transformed
  // object-space closed forms; the normal is the inverse-transpose image of the object normal
  // (so "outward" survives reflections) and dn/du, dn/dv follow from the Weingarten equations
  // applied to the world-space derivatives, hence are exact for any affine transform.
  Hit surface_at(const Vec2& uv) const;

  // Nearest hit with t in (tmin, tmax): ray moved to object space, intersected in double, the
  // hit re-projected onto the surface (Hit::t is the ray parameter of the intersector).
  std::optional<Hit> intersect(const Ray& ray, double tmin, double tmax) const;
  bool intersects(const Ray& ray, double tmin, double tmax) const;

  // World bounds, conservative (corners of the object box, inflated for float rounding).
  Bounds3 world_bounds() const;

  // Area sampling: object-space sampler, density converted to world area by the ratio of the
  // area elements |pu x pv| (exact for any affine transform).
  AreaSample sample_area(const Vec2& u) const;
  double pdf_area(const Vec2& uv) const;

 private:
  Vec3 object_normal(const SurfaceDerivatives& s) const;
  std::shared_ptr<const AnalyticShape> shape_;
  AffineTransform xf_;
  bool flip_;
};

}  // namespace tb

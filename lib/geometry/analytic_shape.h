// Interface of the analytic shapes (sphere, disk, rectangle, cylinder, paraboloid, torus) in
// their object space. Each is a parametric surface p(u, v) on [0, 1]^2 with closed-form first
// and second derivatives, a double-precision ray intersector and area sampling. The world-space
// placement (transform, orientation) and the Embree binding live in ShapeInstance.
//
// Orientation convention: the normal is normalize(dp/du x dp/dv), which points outward for the
// closed shapes (sphere, torus), away from the axis for the cylinder, +z for disk and rectangle
// and away from the axis/downward for the paraboloid.
#pragma once

#include <optional>
#include <string>

#include "lib/core/math.h"
#include "lib/geometry/bounds.h"
#include "lib/geometry/weingarten.h"

namespace tb {

class AnalyticShape {
 public:
  virtual ~AnalyticShape() = default;
  virtual std::string name() const = 0;

  // p(u, v) and its derivatives; exact to double rounding.
  virtual SurfaceDerivatives derivatives(const Vec2& uv) const = 0;
  // The (u, v) of the surface point closest to p (p near the surface): used to re-project a
  // ray hit o + t d onto the surface, which makes hit points exact to double rounding.
  virtual Vec2 project(const Vec3& p) const = 0;
  // Nearest hit of o + t d with t in (tmin, tmax), computed in double. d need not be unit.
  virtual std::optional<double> intersect(const Vec3& o, const Vec3& d, double tmin, double tmax) const = 0;
  virtual Bounds3 bounds() const = 0;
  virtual bool closed() const = 0;
  virtual double area() const = 0;

  // Area sampling: (u, v) from two uniforms, and the density of that (u, v) in the AREA
  // measure of object space (1/area() for the uniform samplers). The density in the (u, v)
  // measure is pdf_area(uv) * |dp/du x dp/dv|.
  virtual Vec2 sample_uv(const Vec2& u) const = 0;
  virtual double pdf_area(const Vec2& uv) const { (void)uv; return 1.0 / area(); }

  // Relative size of the error of a re-projected hit point: |p - p_exact| <= factor * eps *
  // max_i |p_i| in every component, with p in object space. Covers the trigonometric functions (libm is
  // accurate to ~1 ulp) and the few roundings of the closed forms, plus the error of the
  // intersector seen by a ray leaving the surface (see docs/geometry.md).
  virtual double error_factor() const { return 32.0; }
  // Extra absolute object-space error bound (e.g. tube radius for the quartic torus).
  virtual double error_scale() const { return 0.0; }
};

}  // namespace tb

#include "lib/geometry/reference_shapes.h"

#include <memory>

#include "lib/geometry/cylinder.h"
#include "lib/geometry/disk.h"
#include "lib/geometry/paraboloid.h"
#include "lib/geometry/rectangle.h"
#include "lib/geometry/sphere.h"
#include "lib/geometry/torus.h"

namespace tb {

std::vector<ReferenceShape> reference_analytic_shapes() {
  // A generic rigid placement: rotated about a skew axis and moved off the origin, so that no
  // coordinate is special and world coordinates carry rounding of their own.
  const AffineTransform rigid =
      AffineTransform::translate(Vec3(0.3, -1.7, 2.2)) * AffineTransform::rotate(0.7, Vec3(1, 2, 3));
  const AffineTransform aniso = rigid * AffineTransform::scale(Vec3(1.3, 0.8, 1.1));
  std::vector<ReferenceShape> out;
  auto add = [&](std::string name, std::shared_ptr<const AnalyticShape> s, const AffineTransform& xf) {
    ShapeInstance inst(std::move(s), xf);
    const double scale = glm::length(inst.world_bounds().diagonal());
    out.push_back({std::move(name), std::move(inst), scale});
  };
  add("sphere", std::make_shared<Sphere>(0.9), rigid);
  add("sphere_aniso", std::make_shared<Sphere>(0.9), aniso);
  add("disk", std::make_shared<Disk>(1.1), rigid);
  add("annulus", std::make_shared<Disk>(1.1, 0.4), rigid);
  add("rectangle", std::make_shared<Rectangle>(0.8, 0.5), rigid);
  add("cylinder", std::make_shared<Cylinder>(0.6, -0.5, 0.9), rigid);
  add("paraboloid", std::make_shared<Paraboloid>(0.8, 1.2), rigid);
  add("torus", std::make_shared<Torus>(1.0, 0.35), rigid);
  add("torus_aniso", std::make_shared<Torus>(1.0, 0.35), aniso);
  return out;
}

}  // namespace tb

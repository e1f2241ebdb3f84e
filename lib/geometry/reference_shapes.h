// The named shape configurations that tests, checks and benchmarks run over: every analytic
// shape under a non-trivial rigid or scaled transform, and triangle meshes. One list, so that a
// new shape is tested everywhere by adding it here.
#pragma once

#include <string>
#include <vector>

#include "lib/geometry/shape_instance.h"

namespace tb {

struct ReferenceShape {
  std::string name;          // "sphere", "torus", ... (used in check names)
  ShapeInstance instance;
  double scale;              // size of the shape in world units (bounding-box diagonal)
};

// Sphere, disk, annulus, rectangle, cylinder, paraboloid, torus (rotated, translated; the
// "_aniso" variants with a non-uniform scale).
std::vector<ReferenceShape> reference_analytic_shapes();

}  // namespace tb

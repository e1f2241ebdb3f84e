// Rays in double precision. Embree's float rays are made from these at the query boundary
// (lib/geometry); everything above works in double.
#pragma once

#include "lib/core/math.h"

namespace tb {

struct Ray {
  Vec3 o{0.0};
  Vec3 d{0.0, 0.0, 1.0};  // not necessarily normalised unless a routine says so
  double t_min = 0.0;
  double t_max = kInfinity;

  Vec3 at(double t) const { return o + t * d; }
};

// Ray differentials (Igehy 1999): the origins and directions of the two offset rays one
// pixel over in x and in y, carried with the central ray.
struct RayDifferential : Ray {
  bool has_differentials = false;
  Vec3 rx_o{0.0}, rx_d{0.0}, ry_o{0.0}, ry_d{0.0};
};

}  // namespace tb

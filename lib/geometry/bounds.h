// Axis-aligned boxes in double precision.
#pragma once

#include "lib/core/math.h"

namespace tb {

struct Bounds3 {
  Vec3 lo{kInfinity};
  Vec3 hi{-kInfinity};

  void extend(const Vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  Vec3 corner(int i) const { return {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z}; }
  Vec3 diagonal() const { return hi - lo; }
};

}  // namespace tb

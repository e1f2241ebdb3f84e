// RGB spectrum: three doubles with component-wise arithmetic.
#pragma once

#include "lib/core/math.h"

namespace tb {

using Rgb = glm::dvec3;

inline double luminance(const Rgb& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }
// max_component(const Rgb&): lib/core/math.h (Rgb is Vec3).
inline bool is_black(const Rgb& c) { return c.r == 0 && c.g == 0 && c.b == 0; }

}  // namespace tb

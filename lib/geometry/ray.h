// Rays are tb::Ray from lib/core/ray.h (double precision, with t_min / t_max). Embree traces
// float rays; the scene converts at the boundary (scene.cpp) and analytic shapes are
// intersected with the double ray itself.
#pragma once

#include "lib/core/ray.h"

namespace tb {

// Relative shortening of a shadow ray towards a point at t = 1 (pbrt-v4 ShadowEpsilon): the
// target surface is offset by its own error bound, so this only guards the last few ulps.
inline constexpr double kShadowEpsilon = 1e-4;

}  // namespace tb

// Derivatives of the unit normal of a parametric surface from its first and second
// derivatives: the Weingarten equations (do Carmo 1976, Sec. 3-3; pbrt-v3 Eq. 3.10).
#pragma once

#include "lib/core/math.h"

namespace tb {

// p(u, v) and its partial derivatives up to second order, at one (u, v).
struct SurfaceDerivatives {
  Vec3 p{0.0}, pu{0.0}, pv{0.0}, puu{0.0}, puv{0.0}, pvv{0.0};
};

// dn/du, dn/dv of the unit normal n (either orientation of pu x pv). Exact where the
// parameterisation is regular (EG - F^2 > 0); zero at singular points (poles, apexes).
inline void weingarten(const SurfaceDerivatives& s, const Vec3& n, Vec3* dndu, Vec3* dndv) {
  const double E = glm::dot(s.pu, s.pu), F = glm::dot(s.pu, s.pv), G = glm::dot(s.pv, s.pv);
  const double e = glm::dot(n, s.puu), f = glm::dot(n, s.puv), g = glm::dot(n, s.pvv);
  const double egf2 = difference_of_products(E, G, F, F);
  if (!(egf2 > 0)) {
    *dndu = *dndv = Vec3(0.0);
    return;
  }
  const double inv = 1.0 / egf2;
  *dndu = ((f * F - e * G) * inv) * s.pu + ((e * F - f * E) * inv) * s.pv;
  *dndv = ((g * F - f * G) * inv) * s.pu + ((f * F - g * E) * inv) * s.pv;
}

}  // namespace tb

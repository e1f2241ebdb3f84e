// Generalised half vectors and their Jacobians (Kaplanyan, Hanika, Dachsbacher 2014, App. A;
// Walter et al. 2007, Sec. 5.2-5.3). i and o both point away from the vertex; eta_i and eta_o
// are the refractive indices of the media that i and o lie in (equal for reflection).
#pragma once

#include "lib/core/math.h"

namespace tb {

// Unnormalised generalised half vector H = eta_i i + eta_o o. Kaplanyan App. A writes
// h = (i + eta o)/|i + eta o| with eta = eta_o / eta_i, i.e. H/|H|; Walter Eq. 16 writes
// h_t = -H/|H|. For reflection H = eta (i + o), the classic half vector.
inline Vec3 generalized_half_vector_unnormalized(const Vec3& i, const Vec3& o, double eta_i, double eta_o) {
  return eta_i * i + eta_o * o;
}

// h = +-H/|H|, oriented into the hemisphere of `n` (the macro normal, usually +z) so that it is a
// microfacet normal with D(h) > 0; the sign does not change any density or Jacobian below.
// Returns the zero vector when H = 0 (i = -o with eta_i = eta_o: no refraction happens there).
inline Vec3 generalized_half_vector(const Vec3& i, const Vec3& o, double eta_i, double eta_o,
                                    const Vec3& n = Vec3(0, 0, 1)) {
  const Vec3 H = generalized_half_vector_unnormalized(i, o, eta_i, eta_o);
  const double len = glm::length(H);
  if (!(len > 0)) return Vec3(0.0);
  const Vec3 h = H / len;
  return glm::dot(h, n) < 0 ? -h : h;
}

// |d omega_h / d omega_o|: solid angle of h per solid angle of o at fixed i,
//   eta_o^2 |<h, o>| / (eta_i <h, i> + eta_o <h, o>)^2
// (Kaplanyan et al. 2014, Eq. 10 with eta = eta_o / eta_i; Walter et al. 2007, Eq. 14 and 16).
// Derivation: dh = (I - h h^T) eta_o do / |H|; the area of a solid-angle element do around o
// projects onto the plane normal to h with factor |<h, o>|, so |dh/do| = eta_o^2 |<h,o>| / |H|^2,
// and |H| = |<h, H>| = |eta_i <h,i> + eta_o <h,o>|. For reflection this is 1 / (4 |<h, o>|).
// Independent of the sign of h.
inline double half_vector_jacobian(const Vec3& i, const Vec3& o, double eta_i, double eta_o) {
  const Vec3 H = generalized_half_vector_unnormalized(i, o, eta_i, eta_o);
  const double len2 = glm::dot(H, H);
  if (!(len2 > 0)) return kInfinity;
  const Vec3 h = H / std::sqrt(len2);
  // (eta_i <h,i> + eta_o <h,o>)^2 = <h,H>^2 = |H|^2 exactly; |H|^2 avoids the cancellation.
  return eta_o * eta_o * std::abs(glm::dot(h, o)) / len2;
}

}  // namespace tb

#include "lib/material/fresnel.h"

#include <cmath>

namespace tb {

double fresnel_dielectric(double cos_i, double eta) {
  cos_i = std::min(1.0, std::abs(cos_i));
  const double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0) return 1.0;  // total internal reflection
  const double cos_t = std::sqrt(1.0 - sin2_t);
  // Fresnel amplitude coefficients (Born & Wolf Eq. 1.5.21, written with eta = n_t / n_i).
  const double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const double rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

double fresnel_conductor(double cos_i, std::complex<double> eta) {
  using C = std::complex<double>;
  cos_i = std::min(1.0, std::abs(cos_i));
  const double sin2_i = 1.0 - cos_i * cos_i;
  // Snell's law with a complex index: cos_t = sqrt(1 - sin^2_i / eta^2) (principal branch).
  const C cos_t = std::sqrt(C(1.0) - sin2_i / (eta * eta));
  const C rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const C rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5 * (std::norm(rs) + std::norm(rp));
}

Rgb fresnel_conductor(double cos_i, const Rgb& eta, const Rgb& k) {
  return {fresnel_conductor(cos_i, {eta.r, k.r}), fresnel_conductor(cos_i, {eta.g, k.g}),
          fresnel_conductor(cos_i, {eta.b, k.b})};
}

}  // namespace tb

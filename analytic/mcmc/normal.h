// Standard-normal helpers for the MCMC targets and proposals: density, CDF (Boost.Math), and a
// draw by inversion of one uniform (so a draw consumes exactly one uniform, as proposals and
// primary-sample-space states expect).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>

#include <boost/math/distributions/normal.hpp>

#include "lib/core/math.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

template <size_t N>
using Point = std::array<double, N>;

// N(x; mu, sigma^2), Lebesgue measure on R.
inline double normal_pdf(double x, double mu, double sigma) {
  const double z = (x - mu) / sigma;
  return std::exp(-0.5 * z * z) / (sigma * std::sqrt(2.0 * kPi));
}
inline double normal_cdf(double x, double mu, double sigma) {
  if (x == kInfinity) return 1.0;
  if (x == -kInfinity) return 0.0;
  return boost::math::cdf(boost::math::normal(mu, sigma), x);
}
// Phi(b) - Phi(a) computed in the tail that keeps accuracy.
inline double normal_mass(double a, double b, double mu, double sigma) {
  if (a >= mu) return normal_cdf(2 * mu - a, mu, sigma) - normal_cdf(2 * mu - b, mu, sigma);
  return normal_cdf(b, mu, sigma) - normal_cdf(a, mu, sigma);
}
// Phi^{-1}(u) for u in [0, 1): shifted by half an ulp of the uniform grid so it never hits 0.
inline double standard_normal(Uniforms& u) {
  const double v = u.next() + 0x1p-54;
  return boost::math::quantile(boost::math::normal(), v);
}

}  // namespace tb::mcmc

// The normal distribution N(mu, sigma^2) truncated to [a, b], sampled by inverse CDF with
// Boost.Math (erf, erfc, their inverses, normal quantiles). It is the polar-angle kernel of
// the lens and multi-chain perturbations of regional adaptive MLT (Otsu et al., Sec. 3,
// "Perturbing Ray Directions": theta' ~ truncated normal on [-pi, pi] with scale sigma).
//
// Density, with respect to LEBESGUE measure (length) on [a, b]:
//   p(x) = phi((x - mu)/sigma) / (sigma * Z),  Z = Phi(beta) - Phi(alpha),
//   alpha = (a - mu)/sigma, beta = (b - mu)/sigma.
//
// Robustness (docs/sampling.md): the interval is mirrored so that its mass lies on the
// upper side of the mean; masses and quantiles are taken from erf near the mean (where erf
// has full relative precision, so sigma >> b - a is fine) and from the upper-tail function
// Q = 1 - Phi away from it (so a mean far outside [a, b] is fine). When the interval is
// more than ~30 standard deviations from the mean the computation runs in long double
// (Q underflows double near 37 sigma, long double near 150 sigma); beyond that create()
// returns an empty optional. Intervals so narrow that the density is nearly linear across
// them use Gauss-Legendre masses and Newton quantiles (differences of erf would cancel).
#pragma once

#include <cmath>
#include <optional>

namespace tb {

class TruncatedNormal {
 public:
  // Empty when sigma <= 0, a >= b, a parameter is NaN, or the mass of [a, b] underflows.
  // a = -inf and b = +inf are allowed.
  static std::optional<TruncatedNormal> create(double mu, double sigma, double a, double b);

  // Inverse CDF: u in [0, 1) -> x in [a, b].
  double sample(double u) const;
  // Density on [a, b] (Lebesgue measure), 0 outside.
  double pdf(double x) const;
  // CDF, the inverse of sample: cdf(sample(u)) = u up to round-off.
  double cdf(double x) const;

  double mu() const { return mu_; }
  double sigma() const { return sigma_; }
  double a() const { return a_; }
  double b() const { return b_; }
  // ln Z, the log of the untruncated normal's mass on [a, b].
  double log_mass() const { return static_cast<double>(std::log(mass_)); }

 private:
  TruncatedNormal() = default;
  double mu_ = 0, sigma_ = 1, a_ = 0, b_ = 1;
  bool mirrored_ = false;     // standardized interval is [lo, hi] = -[beta, alpha]
  bool long_double_ = false;  // far tail: evaluate in long double
  bool narrow_ = false;       // narrow interval: quadrature masses, Newton quantiles
  double lo_ = 0, hi_ = 1;    // standardized, mirrored interval, lo + hi >= 0
  long double mass_ = 1;      // Z, in long double so that it survives the far tail
};

}  // namespace tb

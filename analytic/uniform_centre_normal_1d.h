// A marginal 1D technique whose marginal density has a closed form, so that continuous MIS (CMIS,
// estimators/cmis.h), which evaluates the marginal at every sample, can be checked at the sample
// sizes of the unbiasedness checks (the quadrature marginal of ConditionalNormal1D costs about a
// thousand conditional evaluations per sample):
//   t ~ U[t_lo, t_hi]                                   p(t) = 1 / (t_hi - t_lo)
//   x | t ~ (1 - ε) N(t, sigma²) + ε U[0, 1]             (the normal is not truncated)
//   p(x) = ∫ p(t) p(x | t) dt = (1 - ε) [Φ((x - t_lo)/sigma) - Φ((x - t_hi)/sigma)] / (t_hi - t_lo) + ε [0 ≤ x ≤ 1].
// Samples may fall outside [0, 1], where the catalogue integrands vanish. Densities in Lebesgue measure.
#pragma once

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/normal.hpp>

#include "analytic/truncated_normal_1d.h"
#include "lib/core/uniforms.h"

namespace tb {

class UniformCentreNormal1D {
 public:
  struct Aux {
    double t = 0.0;
  };
  using Sample = double;

  UniformCentreNormal1D(double t_lo, double t_hi, double sigma, double defensive, std::string name = "")
      : t_lo_(t_lo), t_hi_(t_hi), sigma_(sigma), defensive_(defensive), name_(std::move(name)) {
    if (!(t_hi > t_lo) || !(sigma > 0.0) || defensive < 0.0 || defensive > 1.0)
      throw std::invalid_argument("UniformCentreNormal1D: need t_lo < t_hi, sigma > 0, defensive in [0, 1]");
    inv_sigma_ = 1.0 / sigma;
    norm_ = (1.0 - defensive) / (sigma * std::sqrt(2.0 * 3.14159265358979323846));
  }

  std::optional<Aux> sample_aux(Uniforms& u) const { return Aux{t_lo_ + u.next() * (t_hi_ - t_lo_)}; }
  std::optional<double> sample(const Aux& a, Uniforms& u) const {
    if (defensive_ > 0.0 && u.next() < defensive_) return u.next();
    const double r = u.next();
    if (r <= 0.0) return std::nullopt;  // Φ⁻¹(0) = -∞: a failed draw of probability 2⁻⁵³
    return a.t + sigma_ * boost::math::quantile(truncated_normal_detail::Normal{}, r);
  }
  // p(x | t).
  double pdf(double x, const Aux& a) const {
    const double z = (x - a.t) * inv_sigma_;
    return norm_ * std::exp(-0.5 * z * z) + (defensive_ > 0.0 && x >= 0.0 && x <= 1.0 ? defensive_ : 0.0);
  }
  // p(t).
  double aux_pdf(const Aux& a) const { return (a.t >= t_lo_ && a.t <= t_hi_) ? 1.0 / (t_hi_ - t_lo_) : 0.0; }
  // p(x) in closed form (header comment). The difference of normal CDFs is taken in the tail where
  // both terms are small, so it keeps its relative accuracy away from [t_lo, t_hi].
  double marginal_pdf(double x) const {
    const double a = (x - t_lo_) * inv_sigma_, b = (x - t_hi_) * inv_sigma_;  // a > b
    const double s = 1.0 / std::sqrt(2.0);
    const double mass = b > 0.0 ? 0.5 * (std::erfc(b * s) - std::erfc(a * s)) : 0.5 * (std::erfc(-a * s) - std::erfc(-b * s));
    return (1.0 - defensive_) * mass / (t_hi_ - t_lo_) + (x >= 0.0 && x <= 1.0 ? defensive_ : 0.0);
  }

  double t_lo() const { return t_lo_; }
  double t_hi() const { return t_hi_; }
  double sigma() const { return sigma_; }
  double defensive() const { return defensive_; }
  const std::string& name() const { return name_; }

 private:
  double t_lo_, t_hi_, sigma_, defensive_;
  double inv_sigma_ = 1.0, norm_ = 0.0;
  std::string name_;
};

}  // namespace tb

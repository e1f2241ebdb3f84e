// A normal distribution N(mu, sigma²) truncated to [lo, hi]: sampling by inversion and its density
// (Lebesgue measure on the real line). Written here because lib/core/truncated_normal.h did not
// exist yet when analytic/ was started; CDF and quantile come from Boost.Math (never hand-written).
// Inversion is done on the side of the mean where the truncated mass sits in the lower tail
// (mirroring when lo > mu), so Φ values stay relatively accurate far in the tails.
// Boost.Math is used with promote_double<false>: by default it evaluates double functions in
// long double (x87), which made drawing a (t, x) pair cost ~0.6 µs and dominate the MMIS
// benchmark; in double the results stay within a few ulp (tests/analytic).
#pragma once

#include <algorithm>
#include <cmath>

#include <boost/math/distributions/normal.hpp>

namespace tb {

namespace truncated_normal_detail {
using Policy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;
using Normal = boost::math::normal_distribution<double, Policy>;
}  // namespace truncated_normal_detail

class TruncatedNormal1D {
 public:
  TruncatedNormal1D() = default;
  TruncatedNormal1D(double mu, double sigma, double lo, double hi) : mu_(mu), sigma_(sigma), lo_(lo), hi_(hi) {
    const truncated_normal_detail::Normal n;
    a_ = (lo - mu) / sigma;
    b_ = (hi - mu) / sigma;
    mirrored_ = a_ > 0.0;
    if (mirrored_) {  // P(a < Z < b) = P(-b < Z < -a), computed in the lower tail
      ca_ = boost::math::cdf(n, -b_);
      cb_ = boost::math::cdf(n, -a_);
    } else {
      ca_ = boost::math::cdf(n, a_);
      cb_ = boost::math::cdf(n, b_);
    }
    mass_ = cb_ - ca_;
    inv_norm_ = 1.0 / (sigma * std::sqrt(2.0 * 3.14159265358979323846) * mass_);
  }

  // x from one uniform u in [0, 1).
  double sample(double u) const {
    const truncated_normal_detail::Normal n;
    const double p = std::clamp(ca_ + u * mass_, ca_, cb_);
    double z;
    if (p <= 0.0)
      z = mirrored_ ? -b_ : a_;
    else if (p >= 1.0)
      z = mirrored_ ? -a_ : b_;
    else
      z = boost::math::quantile(n, p);
    if (mirrored_) z = -z;
    return std::clamp(mu_ + sigma_ * z, lo_, hi_);
  }

  // Density in x (Lebesgue measure); zero outside [lo, hi].
  double pdf(double x) const {
    if (x < lo_ || x > hi_) return 0.0;
    const double z = (x - mu_) / sigma_;
    return inv_norm_ * std::exp(-0.5 * z * z);
  }

  // Probability of [lo, hi] under the untruncated normal.
  double mass() const { return mass_; }
  double mu() const { return mu_; }
  double sigma() const { return sigma_; }
  double lo() const { return lo_; }
  double hi() const { return hi_; }

 private:
  double mu_ = 0.5, sigma_ = 1.0, lo_ = 0.0, hi_ = 1.0;
  double a_ = 0.0, b_ = 0.0, ca_ = 0.0, cb_ = 1.0, mass_ = 1.0, inv_norm_ = 1.0;
  bool mirrored_ = false;
};

}  // namespace tb

#include "lib/core/truncated_normal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/special_functions/erf.hpp>

#include "lib/core/math.h"

namespace tb {
namespace {

namespace bm = boost::math;

// Beyond this standardized distance the upper-tail mass Q approaches the double underflow
// threshold (Q(37.5) ~ 1e-308), so the computation switches to long double.
constexpr double kLongDoubleFrom = 30.0;
// Below this standardized distance from the mean erf differences are used (erf has full
// relative precision near 0, erfc does not); above it, upper-tail differences.
constexpr double kTailFrom = 0.5;

// An interval is "narrow" when the normal density changes by less than ~e^0.1 across it:
// width * max(1, |x|) < kNarrow. There differences of erf or erfc cancel, so masses are
// integrated with Gauss-Legendre quadrature of the density (exact to round-off for such a
// smooth, nearly linear integrand) and quantiles are found by safeguarded Newton steps.
constexpr double kNarrow = 0.1;

template <class R>
struct Std {
  static R sqrt2() { return std::sqrt(R(2)); }
  static R q(R x) { return bm::erfc(x / sqrt2()) / 2; }         // upper tail 1 - Phi(x)
  static R erf_half(R x) { return bm::erf(x / sqrt2()) / 2; }   // Phi(x) - 1/2
  static R q_inv(R p) {
    // u = 0 with an infinite bound: the most extreme representable quantile, not infinity.
    if (p <= 0) p = std::numeric_limits<R>::denorm_min();
    return bm::quantile(bm::complement(bm::normal_distribution<R>(), p));
  }
  static R erf_half_inv(R v) { return sqrt2() * bm::erf_inv(2 * v); }

  // Mass of the standard normal on [x0, x1], x0 <= x1, chosen to avoid cancellation.
  static R mass(R x0, R x1) {
    if (x1 <= 0) return mass(-x1, -x0);
    if (x0 >= kTailFrom) return q(x0) - q(x1);
    if (x0 >= 0) return erf_half(x1) - erf_half(x0);
    return erf_half(x1) + erf_half(-x0);  // straddles the mean: a sum, no cancellation
  }

  static R density(R x) { return std::exp(-x * x / 2) / std::sqrt(2 * R(3.14159265358979323846264338327950288L)); }
  static R mass_narrow(R x0, R x1) {
    return boost::math::quadrature::gauss<R, 20>::integrate([](R x) { return density(x); }, x0, x1);
  }
  // xi in [lo, hi] with mass(lo, xi) = u_lo z for a narrow interval: Newton steps on the
  // quadrature mass from the nearer end, kept inside a shrinking bracket.
  static R quantile_narrow(R lo, R hi, R z, R u_lo, R u_hi) {
    const bool from_lo = u_lo <= u_hi;
    R a = lo, b = hi, xi = lo + u_lo * (hi - lo);
    for (int it = 0; it < 50; ++it) {
      const R g = from_lo ? mass_narrow(lo, xi) - u_lo * z : u_hi * z - mass_narrow(xi, hi);  // increasing in xi
      if (g == 0) break;
      (g > 0 ? b : a) = xi;
      R next = xi - g / density(xi);
      if (!(next > a && next < b)) next = (a + b) / 2;
      if (std::abs(next - xi) <= std::numeric_limits<R>::epsilon() * std::max(std::abs(xi), R(1e-300))) {
        xi = next;
        break;
      }
      xi = next;
    }
    return xi;
  }

  // xi in [lo, hi] with mass(lo, xi) = u_lo * Z and mass(xi, hi) = u_hi * Z, u_lo + u_hi = 1.
  // The formula is chosen on the side where the answer lies (both u's are passed so neither
  // loses precision to 1 - u).
  static R quantile(R lo, R hi, R z, R u_lo, R u_hi) {
    const R v = erf_half(std::max(lo, R(-40))) + u_lo * z;  // Phi(xi) - 1/2 (coarse, for the branch)
    if (lo >= kTailFrom) return q_inv(q(hi) + u_hi * z);  // whole interval in the upper tail
    if (v > erf_half(R(kTailFrom))) return q_inv(q(hi) + u_hi * z);
    if (v < -erf_half(R(kTailFrom))) return -q_inv(q(-lo) + u_lo * z);
    return erf_half_inv(v);
  }
};


}  // namespace

std::optional<TruncatedNormal> TruncatedNormal::create(double mu, double sigma, double a, double b) {
  if (!(sigma > 0) || !(a < b) || !std::isfinite(mu) || !std::isfinite(sigma)) return std::nullopt;
  TruncatedNormal t;
  t.mu_ = mu;
  t.sigma_ = sigma;
  t.a_ = a;
  t.b_ = b;
  const double alpha = (a - mu) / sigma, beta = (b - mu) / sigma;
  if (std::isnan(alpha) || std::isnan(beta) || !(alpha < beta)) return std::nullopt;
  t.mirrored_ = alpha + beta < 0;
  t.lo_ = t.mirrored_ ? -beta : alpha;
  t.hi_ = t.mirrored_ ? -alpha : beta;
  t.long_double_ = t.lo_ > kLongDoubleFrom;
  t.narrow_ = std::isfinite(t.lo_) && std::isfinite(t.hi_) &&
              (t.hi_ - t.lo_) * std::max({1.0, std::abs(t.lo_), std::abs(t.hi_)}) < kNarrow;
  if (t.narrow_)
    t.mass_ = t.long_double_ ? Std<long double>::mass_narrow(t.lo_, t.hi_) : Std<double>::mass_narrow(t.lo_, t.hi_);
  else
    t.mass_ = t.long_double_ ? Std<long double>::mass(t.lo_, t.hi_) : Std<double>::mass(t.lo_, t.hi_);
  if (!(t.mass_ > 0) || !std::isfinite(std::log(t.mass_))) return std::nullopt;
  return t;
}

namespace {
template <class R>
double sample_impl(double lo, double hi, long double mass, bool mirrored, bool narrow, double u) {
  const R z = static_cast<R>(mass);
  const R u_lo = mirrored ? R(1) - R(u) : R(u);
  const R u_hi = mirrored ? R(u) : R(1) - R(u);
  const R xi = narrow ? Std<R>::quantile_narrow(R(lo), R(hi), z, u_lo, u_hi)
                      : Std<R>::quantile(R(lo), R(hi), z, u_lo, u_hi);
  const double x = std::clamp(static_cast<double>(xi), lo, hi);
  return mirrored ? -x : x;
}
template <class R>
double cdf_impl(double lo, double hi, long double mass, bool mirrored, bool narrow, double xi) {
  // Mirrored: F(x) = P(X' >= xi') with xi' = -xi in the mirrored frame.
  const auto m_of = [narrow](R x0, R x1) { return narrow ? Std<R>::mass_narrow(x0, x1) : Std<R>::mass(x0, x1); };
  const R m = mirrored ? m_of(R(-xi), R(hi)) : m_of(R(lo), R(xi));
  return static_cast<double>(m / static_cast<R>(mass));
}
}  // namespace

double TruncatedNormal::sample(double u) const {
  const double xi = long_double_ ? sample_impl<long double>(lo_, hi_, mass_, mirrored_, narrow_, u)
                                 : sample_impl<double>(lo_, hi_, mass_, mirrored_, narrow_, u);
  return std::clamp(mu_ + sigma_ * xi, a_, b_);
}

double TruncatedNormal::pdf(double x) const {
  if (!(x >= a_ && x <= b_)) return 0.0;
  const double xi = (x - mu_) / sigma_;
  // phi(xi) / (sigma Z) in log space: both factors underflow together in the far tail.
  const long double log_p = -0.5L * static_cast<long double>(xi) * xi - std::log(mass_);
  return static_cast<double>(std::exp(log_p) / std::sqrt(2.0L * static_cast<long double>(kPi))) / sigma_;
}

double TruncatedNormal::cdf(double x) const {
  if (x <= a_) return 0.0;
  if (x >= b_) return 1.0;
  const double xi = std::clamp((x - mu_) / sigma_, mirrored_ ? -hi_ : lo_, mirrored_ ? -lo_ : hi_);
  const double f = long_double_ ? cdf_impl<long double>(lo_, hi_, mass_, mirrored_, narrow_, xi)
                                : cdf_impl<double>(lo_, hi_, mass_, mirrored_, narrow_, xi);
  return std::clamp(f, 0.0, 1.0);
}

}  // namespace tb

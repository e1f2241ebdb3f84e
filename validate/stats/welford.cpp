#include "validate/stats/welford.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tb::stats {

void Welford::add(double x) {
  if (!std::isfinite(x)) {
    ++nonfinite_;
    return;
  }
  // Pébay 2008, Eq. 2.1-2.2 (one-point update of M2, M3, M4), in the order M4, M3, M2 so that each
  // update uses the previous lower moments.
  const double n1 = static_cast<double>(n_);
  ++n_;
  const double n = static_cast<double>(n_);
  const double delta = x - mean_;
  const double delta_n = delta / n;
  const double delta_n2 = delta_n * delta_n;
  const double term1 = delta * delta_n * n1;
  mean_ += delta_n;
  m4_ += term1 * delta_n2 * (n * n - 3.0 * n + 3.0) + 6.0 * delta_n2 * m2_ - 4.0 * delta_n * m3_;
  m3_ += term1 * delta_n * (n - 2.0) - 3.0 * delta_n * m2_;
  m2_ += term1;
}

void Welford::merge(const Welford& other) {
  nonfinite_ += other.nonfinite_;
  if (other.n_ == 0) return;
  if (n_ == 0) {
    const int64_t nf = nonfinite_;
    *this = other;
    nonfinite_ = nf;
    return;
  }
  // Chan, Golub & LeVeque 1979 (M2); Pébay 2008, Eq. 3.1 specialised to p = 3, 4.
  const double na = static_cast<double>(n_), nb = static_cast<double>(other.n_);
  const double n = na + nb;
  const double delta = other.mean_ - mean_;
  const double d2 = delta * delta, d3 = d2 * delta, d4 = d2 * d2;
  const double m2 = m2_ + other.m2_ + d2 * na * nb / n;
  const double m3 = m3_ + other.m3_ + d3 * na * nb * (na - nb) / (n * n) +
                    3.0 * delta * (na * other.m2_ - nb * m2_) / n;
  const double m4 = m4_ + other.m4_ + d4 * na * nb * (na * na - na * nb + nb * nb) / (n * n * n) +
                    6.0 * d2 * (na * na * other.m2_ + nb * nb * m2_) / (n * n) +
                    4.0 * delta * (na * other.m3_ - nb * m3_) / n;
  mean_ += delta * nb / n;
  m2_ = m2;
  m3_ = m3;
  m4_ = m4;
  n_ += other.n_;
}

double Welford::variance() const { return n_ < 2 ? 0.0 : m2_ / static_cast<double>(n_ - 1); }
double Welford::population_variance() const { return n_ == 0 ? 0.0 : m2_ / static_cast<double>(n_); }
double Welford::std_dev() const { return std::sqrt(variance()); }
double Welford::std_error() const {
  if (n_ < 2) return std::numeric_limits<double>::infinity();
  return std::sqrt(variance() / static_cast<double>(n_));
}
double Welford::central_moment3() const { return n_ == 0 ? 0.0 : m3_ / static_cast<double>(n_); }
double Welford::central_moment4() const { return n_ == 0 ? 0.0 : m4_ / static_cast<double>(n_); }

double Welford::skewness() const {
  const double m2 = population_variance();
  return m2 > 0.0 ? central_moment3() / (m2 * std::sqrt(m2)) : 0.0;
}
double Welford::kurtosis() const {
  const double m2 = population_variance();
  return m2 > 0.0 ? central_moment4() / (m2 * m2) : 0.0;
}

double Welford::variance_std_error() const {
  if (n_ < 4) return std::numeric_limits<double>::infinity();
  const double n = static_cast<double>(n_);
  const double s2 = variance();
  const double v = (central_moment4() - (n - 3.0) / (n - 1.0) * s2 * s2) / n;
  // v >= 0 for every sample: m4 >= m2^2 (Jensen) and (n-3)/(n-1) s^4 = n^2 (n-3)/(n-1)^3 m2^2 < m2^2;
  // clamp only against rounding.
  return std::sqrt(std::max(v, 0.0));
}

}  // namespace tb::stats

// Streaming moments of a sample: count, mean, and the second, third and fourth central moments,
// with an exact parallel merge, so that per-thread or per-replicate accumulators combine into the
// same statistics as one sequential pass (up to rounding).
//
// Update and merge formulas: Welford 1962 (running mean and M2); Chan, Golub & LeVeque 1979
// (pairwise merge of M2); Pébay 2008, "Formulas for robust, one-pass parallel computation of
// covariances and arbitrary-order statistical moments", Sandia SAND2008-6212, Eq. 2.1-2.2 (M3, M4
// update) and Eq. 3.1 (pairwise merge of arbitrary order).
//
// NaN and Inf are never folded into the moments: add() counts them (nonfinite()) and callers
// report the count (STYLE.md, "Numbers").
#pragma once

#include <cstdint>

namespace tb::stats {

class Welford {
 public:
  Welford() = default;

  // Adds one observation. A non-finite x is counted in nonfinite() and otherwise ignored.
  void add(double x);
  // Folds another accumulator into this one; equals adding the other's observations
  // sequentially (Chan et al. 1979; Pébay 2008, Eq. 3.1).
  void merge(const Welford& other);

  int64_t count() const { return n_; }
  int64_t nonfinite() const { return nonfinite_; }
  double mean() const { return mean_; }
  // Unbiased sample variance s^2 = M2 / (n - 1); 0 when n < 2.
  double variance() const;
  // Biased (population) variance m2 = M2 / n; 0 when n == 0.
  double population_variance() const;
  double std_dev() const;
  // Standard error of the mean, sqrt(s^2 / n); +inf when n < 2.
  double std_error() const;
  // Central sample moments m_k = M_k / n (biased, the plug-in estimates).
  double central_moment2() const { return population_variance(); }
  double central_moment3() const;
  double central_moment4() const;
  // Plug-in skewness m3 / m2^1.5 and (non-excess) kurtosis m4 / m2^2; 0 when m2 == 0.
  double skewness() const;
  double kurtosis() const;
  // Standard error of the unbiased sample variance s^2 from the fourth moment:
  //   SE(s^2)^2 ~= (m4 - (n - 3) / (n - 1) * s^4) / n
  // i.e. the exact iid variance Var(s^2) = mu4/n - (n-3)/(n(n-1)) sigma^4 with the plug-in m4 for
  // mu4 and s^2 for sigma^2. Returns +inf when n < 4. Used by the variance-bound checks (docs/validation.md D).
  double variance_std_error() const;

  // Raw accumulators, for serialising and for tests.
  double m2_sum() const { return m2_; }
  double m3_sum() const { return m3_; }
  double m4_sum() const { return m4_; }

 private:
  int64_t n_ = 0;
  int64_t nonfinite_ = 0;
  double mean_ = 0.0;
  double m2_ = 0.0;  // sum of (x - mean)^2
  double m3_ = 0.0;  // sum of (x - mean)^3
  double m4_ = 0.0;  // sum of (x - mean)^4
};

}  // namespace tb::stats

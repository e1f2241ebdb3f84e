// The result of one realisation of an estimator, with its cost. Cost is counted in pdf
// evaluations (West et al. 2022, Sec. 3.2: MMIS_n costs n·N·T of them for a budget of N samples)
// and in samples drawn. Non-finite contributions are counted, never dropped silently.
#pragma once

#include <cmath>
#include <cstdint>

namespace tb {

struct Estimate {
  double value = 0.0;
  int64_t samples = 0;     // x samples requested (including failed ones)
  int64_t failed = 0;      // samples whose sampling routine returned an empty optional
  int64_t pdf_evals = 0;   // evaluations of p(x) or p(x | t)
  int64_t nonfinite = 0;   // contributions that were NaN or Inf (they are added, so the value shows it)

  Estimate& operator+=(const Estimate& o) {
    value += o.value;
    samples += o.samples;
    failed += o.failed;
    pdf_evals += o.pdf_evals;
    nonfinite += o.nonfinite;
    return *this;
  }
  // Adds one contribution f/p-like term, counting it when it is not finite.
  void add(double contribution) {
    if (!std::isfinite(contribution)) ++nonfinite;
    value += contribution;
  }
};

// The quotient f(x) / d with the convention 0 / 0 = 0 (f vanishes where no technique samples).
inline double safe_ratio(double f, double d) { return f == 0.0 ? 0.0 : f / d; }

}  // namespace tb

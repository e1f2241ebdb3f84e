// Tests of the tests, slow: the 99% interval of the fitted exponent covers the true 1/2 at its
// nominal rate, and the "no floor" decision errs at its nominal rate, over many seeded studies.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "validate/stats/convergence_fit.h"
#include "validate/stats/tests.h"

namespace tb::stats {
namespace {

TEST(ConvergenceCoverage, AlphaIntervalAndFloorDecisionAreCalibrated) {
  const Estimator est = [](int64_t n, uint64_t seed) {
    Rng rng(seed);
    double s = 0;
    for (int64_t i = 0; i < n; ++i) s += std::exp(rng.uniform());
    return s / static_cast<double>(n);
  };
  const double truth = std::exp(1.0) - 1.0;
  constexpr int kStudies = 300;
  int alpha_misses = 0, false_floors = 0;
  for (int i = 0; i < kStudies; ++i) {
    ConvergenceStudyOptions o;
    o.log2_min = 4;
    o.log2_max = 12;
    o.replicates = 32;
    o.seed = static_cast<uint64_t>(i);
    o.key = hash_string("ConvergenceCoverage");
    const ConvergenceStudy s = run_convergence_study(est, truth, o);
    alpha_misses += !(s.fit.alpha_lo <= 0.5 && 0.5 <= s.fit.alpha_hi);
    false_floors += s.floor_fit.floor_detected();
  }
  // Each is Binomial(300, 0.01) if calibrated (two-sided binomial test at 1e-3). The floor
  // decision is one-sided (beta_lo > 0), so its nominal rate is 0.005.
  const TestResult a = binomial_test(alpha_misses, kStudies, 0.01);
  const TestResult f = binomial_test(false_floors, kStudies, 0.005);
  std::printf("alpha interval misses %d / %d (p = %.3g), false floors %d / %d (p = %.3g)\n", alpha_misses, kStudies,
              a.p_value, false_floors, kStudies, f.p_value);
  EXPECT_GE(a.p_value, 1e-3) << alpha_misses << " misses of " << kStudies;
  EXPECT_GE(f.p_value, 1e-3) << false_floors << " false floors of " << kStudies;
}

}  // namespace
}  // namespace tb::stats

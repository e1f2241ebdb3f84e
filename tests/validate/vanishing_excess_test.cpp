// The criterion "the extra variance of MMIS_n vanishes" shared by the check mmis.variance_vs_n and
// `tb reproduce mmis-fig1` (validate/checks/estimator_check_helpers.h): it holds for a variance that
// falls onto the reference and fails for each way the claim can be false.
#include <cmath>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/checks/estimator_check_helpers.h"

namespace tb {
namespace {

// Welford moments of n draws of sigma * (a centred uniform scaled to unit variance).
stats::Welford draws(double sigma, int n, uint64_t seed) {
  Rng r(seed);
  stats::Welford w;
  for (int i = 0; i < n; ++i) w.add(sigma * std::sqrt(12.0) * (r.uniform() - 0.5));
  return w;
}

TEST(VanishingExcess, HoldsWhenTheVarianceFallsOntoTheReference) {
  const auto v = checks::vanishing_excess(draws(2.0, 20000, 1), draws(1.0, 20000, 2), 1.0, 0.25, 1e-5);
  EXPECT_TRUE(v.falls);
  EXPECT_TRUE(v.within);
  EXPECT_NEAR(v.ratio_first, 4.0, 0.2);
  EXPECT_NEAR(v.ratio_last, 1.0, 0.05);
}

TEST(VanishingExcess, FailsWhenTheExcessRemains) {
  // Falls from 4x to 2x the reference, but 2x is far outside 1 ± 0.25.
  const auto v = checks::vanishing_excess(draws(2.0, 20000, 3), draws(std::sqrt(2.0), 20000, 4), 1.0, 0.25, 1e-5);
  EXPECT_TRUE(v.falls);
  EXPECT_FALSE(v.within);
  EXPECT_FALSE(v.holds());
}

TEST(VanishingExcess, FailsWithoutAFall) {
  const auto v = checks::vanishing_excess(draws(1.0, 20000, 5), draws(1.0, 20000, 6), 1.0, 0.25, 1e-5);
  EXPECT_FALSE(v.falls);
  EXPECT_FALSE(v.holds());
}

TEST(VanishingExcess, FailsWhenTooFewReplicatesToShowEquivalence) {
  // At the reference, but 50 replicates cannot place the ratio within 1 ± 0.25 at alpha 1e-5.
  const auto v = checks::vanishing_excess(draws(2.0, 20000, 7), draws(1.0, 50, 8), 1.0, 0.25, 1e-5);
  EXPECT_FALSE(v.within);
}

}  // namespace
}  // namespace tb

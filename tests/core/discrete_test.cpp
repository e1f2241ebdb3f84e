#include "lib/core/discrete.h"

#include <vector>

#include <gtest/gtest.h>

#include "lib/core/math.h"

namespace tb {
namespace {

TEST(Discrete, EmptyForInvalidWeights) {
  EXPECT_FALSE(AliasTable::create(std::vector<double>{}));
  EXPECT_FALSE(AliasTable::create(std::vector<double>{0, 0, 0}));
  EXPECT_FALSE(AliasTable::create(std::vector<double>{1, -1, 2}));
  EXPECT_FALSE(DiscreteCdf::create(std::vector<double>{0, 0}));
  EXPECT_FALSE(DiscreteCdf::create(std::vector<double>{1, kInfinity}));
}

// The alias table's probability of each index, computed exactly from its bins by sweeping u
// over a fine grid would be approximate; instead sum bin contributions: P(i) = (q_i + sum over
// bins j aliasing to i of (1 - q_j)) / n. Checked through sampling at the bin-resolution grid
// points where q is resolved: enough to see that zero weights are never chosen.
TEST(Discrete, ZeroWeightsAreNeverSampled) {
  const std::vector<double> w = {0, 3, 0, 0, 1, 0, 2, 0};
  const auto a = AliasTable::create(w);
  const auto c = DiscreteCdf::create(w);
  ASSERT_TRUE(a && c);
  for (int i = 0; i < 100000; ++i) {
    const double u = std::min(i / 100000.0, kOneMinusEpsilon);
    EXPECT_GT(w[a->sample(u).index], 0.0) << "u = " << u;
    EXPECT_GT(w[c->sample(u).index], 0.0) << "u = " << u;
  }
  EXPECT_GT(w[a->sample(kOneMinusEpsilon).index], 0.0);
  EXPECT_GT(w[c->sample(0.0).index], 0.0);
  EXPECT_DOUBLE_EQ(a->pmf(1), 0.5);
  EXPECT_DOUBLE_EQ(c->pmf(6), 2.0 / 6.0);
}

TEST(Discrete, AliasFrequenciesOnAFineGridMatchPmf) {
  // With u on a grid of m points per bin, each index's share is exact up to 1/m per bin.
  const std::vector<double> w = {0.1, 5, 0, 2.5, 1, 0.4, 7};
  const auto a = AliasTable::create(w);
  ASSERT_TRUE(a);
  const int m = 20000 * static_cast<int>(w.size());
  std::vector<double> freq(w.size(), 0);
  for (int i = 0; i < m; ++i) freq[a->sample((i + 0.5) / m).index] += 1.0 / m;
  for (size_t i = 0; i < w.size(); ++i) EXPECT_NEAR(freq[i], a->pmf(i), 2.0 * w.size() / m) << i;
}

TEST(Discrete, CdfInverseRoundTrip) {
  const std::vector<double> w = {0, 1e-12, 3, 0, 1, 2, 0};
  const auto c = DiscreteCdf::create(w);
  ASSERT_TRUE(c);
  for (int i = 0; i < 10000; ++i) {
    const double u = std::min(i / 10000.0 + 1.234e-5, kOneMinusEpsilon);
    const DiscreteSample s = c->sample(u);
    ASSERT_GE(s.u_remapped, 0.0);
    ASSERT_LT(s.u_remapped, 1.0);
    EXPECT_NEAR(c->invert(s.index, s.u_remapped), u, 1e-12);
  }
}

TEST(Discrete, AliasRemappedUniformIsInUnitInterval) {
  const std::vector<double> w = {1, 2, 3, 0, 4};
  const auto a = AliasTable::create(w);
  ASSERT_TRUE(a);
  for (int i = 0; i < 10000; ++i) {
    const DiscreteSample s = a->sample(std::min(i / 10000.0, kOneMinusEpsilon));
    ASSERT_GE(s.u_remapped, 0.0);
    ASSERT_LT(s.u_remapped, 1.0);
  }
}

}  // namespace
}  // namespace tb

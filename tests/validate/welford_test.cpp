#include "validate/stats/welford.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/rng.h"
#include "validate/stats/batch_means.h"

namespace tb::stats {
namespace {

std::vector<double> skewed_samples(uint64_t seed, size_t n) {
  Rng rng(seed);
  std::vector<double> xs(n);
  // Exponential plus an offset: non-zero third and fourth central moments, and a large mean
  // relative to the spread to exercise cancellation.
  for (double& x : xs) x = 1000.0 - std::log1p(-rng.uniform());
  return xs;
}

void expect_rel_near(double a, double b, double rel) { EXPECT_NEAR(a, b, rel * std::max(1e-300, std::fabs(b))) << a << " vs " << b; }

TEST(Welford, MomentsMatchTwoPass) {
  const auto xs = skewed_samples(7, 10000);
  Welford w;
  for (double x : xs) w.add(x);
  double mean = 0;
  for (double x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  double m2 = 0, m3 = 0, m4 = 0;
  for (double x : xs) {
    const double d = x - mean;
    m2 += d * d, m3 += d * d * d, m4 += d * d * d * d;
  }
  expect_rel_near(w.mean(), mean, 1e-13);
  expect_rel_near(w.m2_sum(), m2, 1e-10);
  expect_rel_near(w.m3_sum(), m3, 1e-8);
  expect_rel_near(w.m4_sum(), m4, 1e-9);
  // Exponential(1): variance 1, skewness 2, kurtosis 9.
  EXPECT_NEAR(w.variance(), 1.0, 0.05);
  EXPECT_NEAR(w.skewness(), 2.0, 0.3);
  EXPECT_NEAR(w.kurtosis(), 9.0, 2.5);
}

TEST(Welford, MergeEqualsSequential) {
  const auto xs = skewed_samples(11, 10007);
  Welford seq;
  for (double x : xs) seq.add(x);
  // Uneven chunks merged in a tree and in a chain.
  const std::vector<size_t> cuts = {0, 1, 2, 17, 500, 4096, 4097, 9000, xs.size()};
  std::vector<Welford> parts;
  for (size_t c = 0; c + 1 < cuts.size(); ++c) {
    Welford w;
    for (size_t i = cuts[c]; i < cuts[c + 1]; ++i) w.add(xs[i]);
    parts.push_back(w);
  }
  Welford chain;
  for (const auto& p : parts) chain.merge(p);
  while (parts.size() > 1) {
    std::vector<Welford> next;
    for (size_t i = 0; i < parts.size(); i += 2) {
      Welford w = parts[i];
      if (i + 1 < parts.size()) w.merge(parts[i + 1]);
      next.push_back(w);
    }
    parts = next;
  }
  for (const Welford* m : {&chain, &parts[0]}) {
    EXPECT_EQ(m->count(), seq.count());
    expect_rel_near(m->mean(), seq.mean(), 1e-12);
    expect_rel_near(m->m2_sum(), seq.m2_sum(), 1e-12);
    expect_rel_near(m->m3_sum(), seq.m3_sum(), 1e-10);  // M3 is a difference of large terms
    expect_rel_near(m->m4_sum(), seq.m4_sum(), 1e-12);
  }
  Welford empty;
  Welford copy = seq;
  copy.merge(empty);
  empty.merge(seq);
  EXPECT_EQ(copy.m4_sum(), seq.m4_sum());
  EXPECT_EQ(empty.m4_sum(), seq.m4_sum());
}

TEST(Welford, NonFiniteIsCountedNotAdded) {
  Welford w;
  w.add(1.0);
  w.add(std::numeric_limits<double>::quiet_NaN());
  w.add(std::numeric_limits<double>::infinity());
  w.add(3.0);
  EXPECT_EQ(w.count(), 2);
  EXPECT_EQ(w.nonfinite(), 2);
  EXPECT_DOUBLE_EQ(w.mean(), 2.0);
  EXPECT_DOUBLE_EQ(w.variance(), 2.0);
}

TEST(Welford, VarianceStdErrorMatchesReplicates) {
  // The spread of s^2 over independent replicates must match variance_std_error() (normal data:
  // Var(s^2) = 2 sigma^4 / (n - 1)).
  const int n = 200, reps = 2000;
  Welford s2;
  double se_sum = 0;
  for (int r = 0; r < reps; ++r) {
    Rng rng = Rng::for_sample(3, 99, static_cast<uint64_t>(r));
    Welford w;
    for (int i = 0; i < n; ++i) {
      // Box-Muller normal.
      const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
      w.add(std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.141592653589793 * u2));
    }
    s2.add(w.variance());
    se_sum += w.variance_std_error();
  }
  const double expected = std::sqrt(2.0 / (n - 1));
  EXPECT_NEAR(s2.std_dev(), expected, 0.05 * expected);
  EXPECT_NEAR(se_sum / reps, expected, 0.05 * expected);
}

TEST(BatchMeans, MeansAndTTest) {
  BatchMeans bm(4);
  for (int i = 0; i < 18; ++i) bm.add(static_cast<double>(i));
  ASSERT_EQ(bm.batches(), 4);
  EXPECT_EQ(bm.pending(), 2);
  EXPECT_DOUBLE_EQ(bm.means()[0], 1.5);
  EXPECT_DOUBLE_EQ(bm.means()[3], 13.5);
  EXPECT_NEAR(bm.t_test(7.5).p_value, 1.0, 1e-12);
  const std::vector<double> xs = {1, 2, 3, 4, 5, 6, 7};
  const auto m = batch_means(xs, 3);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_DOUBLE_EQ(m[2], 5.5);
}

}  // namespace
}  // namespace tb::stats

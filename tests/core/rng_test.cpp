#include "lib/core/rng.h"

#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "lib/core/parallel.h"

namespace tb {
namespace {

TEST(Pcg32, AdvanceMatchesStepping) {
  Pcg32 a(7, 11), b(7, 11);
  for (int i = 0; i < 1000; ++i) a.next_u32();
  b.advance(1000);
  EXPECT_EQ(a, b);
  EXPECT_EQ(a.next_u32(), b.next_u32());
}

TEST(Rng, UniformAtIsPureFunctionOfItsArguments) {
  Rng r = Rng::for_sample(42, 3, 9);
  for (uint64_t d = 0; d < 64; ++d) EXPECT_EQ(r.uniform(), Rng::uniform_at(42, 3, 9, d)) << "dim " << d;
}

TEST(Rng, UniformsInUnitInterval) {
  Rng r(1);
  for (int i = 0; i < 100000; ++i) {
    const double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

TEST(Rng, DistinctKeysGiveDistinctStreams) {
  std::set<uint64_t> firsts;
  for (uint64_t key = 0; key < 1000; ++key) firsts.insert(Rng::for_sample(1, key, 0).next_u64());
  EXPECT_EQ(firsts.size(), 1000u);
}

TEST(Rng, UniformBelowIsInRange) {
  Rng r(5);
  for (int i = 0; i < 10000; ++i) ASSERT_LT(r.uniform_below(7), 7u);
}

// Bit-identical results for 1 and 2 threads and for samples visited out of order.
double sum_over_samples(size_t threads, bool reversed) {
  ThreadLimit limit(threads);
  constexpr size_t n = 1 << 14;
  std::vector<double> v(n);
  parallel_for(n, [&](size_t i) {
    const size_t idx = reversed ? n - 1 - i : i;
    Rng r = Rng::for_sample(123, 77, idx);
    v[idx] = r.uniform() * r.uniform();
  });
  CompensatedSum s;
  for (double x : v) s += x;
  return s.value();
}

TEST(Rng, ThreadCountAndOrderDoNotChangeResults) {
  const double a = sum_over_samples(1, false);
  EXPECT_EQ(a, sum_over_samples(2, false));
  EXPECT_EQ(a, sum_over_samples(2, true));
  EXPECT_EQ(a, sum_over_samples(0, true));
}

}  // namespace
}  // namespace tb

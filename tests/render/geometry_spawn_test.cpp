// next_double_up / next_double_down (lib/geometry/spawn.h) against std::nextafter: the bit
// manipulation must give exactly the library's neighbours, signed zeros and infinities included.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "lib/core/rng.h"
#include "lib/geometry/spawn.h"

namespace tb {
namespace {

TEST(Spawn, NextDoubleMatchesNextafter) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 1e-310, -1e-310, std::numeric_limits<double>::denorm_min(),
                                -std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(),
                                -std::numeric_limits<double>::max(), inf, -inf, 0.1, -123.456};
  Rng rng(7);
  for (int i = 0; i < 10000; ++i) values.push_back((rng.uniform() - 0.5) * std::exp2(rng.uniform() * 200 - 100));
  for (double v : values) {
    const double up = next_double_up(v), down = next_double_down(v);
    const double up_ref = std::nextafter(v, inf), down_ref = std::nextafter(v, -inf);
    EXPECT_EQ(std::bit_cast<uint64_t>(up), std::bit_cast<uint64_t>(up_ref)) << v;
    EXPECT_EQ(std::bit_cast<uint64_t>(down), std::bit_cast<uint64_t>(down_ref)) << v;
  }
}

}  // namespace
}  // namespace tb

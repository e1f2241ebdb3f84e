// next_double_up / next_double_down (lib/geometry/spawn.h) against std::nextafter: the bit
// manipulation must give exactly the library's neighbours, signed zeros and infinities included;
// and the branch-free next_double_toward against them.
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

TEST(Spawn, NextDoubleTowardMatchesUpDown) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 1e-310, -1e-310, std::numeric_limits<double>::denorm_min(),
                                -std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(),
                                -std::numeric_limits<double>::max(), inf, -inf, 0.1, -123.456};
  Rng rng(9);
  for (int i = 0; i < 10000; ++i) values.push_back((rng.uniform() - 0.5) * std::exp2(rng.uniform() * 200 - 100));
  for (double v : values)
    for (double dir : {1e-300, 0.5, -1e-300, -0.5, 0.0, -0.0}) {
      const double ref = dir > 0 ? next_double_up(v) : (dir < 0 ? next_double_down(v) : v);
      EXPECT_EQ(std::bit_cast<uint64_t>(next_double_toward(v, dir)), std::bit_cast<uint64_t>(ref)) << v << " " << dir;
    }
}

}  // namespace
}  // namespace tb

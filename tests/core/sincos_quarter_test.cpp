// sincos_quarter (lib/core/sincos_quarter.h) against libm sin / cos on [-pi/4, pi/4]: within two ulps.
#include "lib/core/sincos_quarter.h"

#include <gtest/gtest.h>

#include "lib/core/rng.h"

namespace tb {
namespace {

// Distance in units in the last place of `ref` (the libm value, itself within an ulp of exact).
double ulps(double v, double ref) {
  if (v == ref) return 0.0;
  return std::abs(v - ref) / (std::nextafter(std::abs(ref), kInfinity) - std::abs(ref));
}

// The polynomial's truncation error is < 3e-18 (header); what remains is rounding, a couple of
// ulps at most for Horner's rule with the leading term added last, plus libm's own half ulp.
constexpr double kMaxUlps = 2.0;

TEST(SinCosQuarter, MatchesLibmWithinTwoUlps) {
  Rng rng(7);
  double worst_s = 0, worst_c = 0;
  for (int i = 0; i < 1000000; ++i) {
    const double x = kPiOver4 * (2.0 * rng.uniform() - 1.0);
    double s, c;
    sincos_quarter(x, &s, &c);
    worst_s = std::max(worst_s, ulps(s, std::sin(x)));
    worst_c = std::max(worst_c, ulps(c, std::cos(x)));
  }
  EXPECT_LE(worst_s, kMaxUlps);
  EXPECT_LE(worst_c, kMaxUlps);
}

TEST(SinCosQuarter, EndpointsAndTinyArguments) {
  for (double x : {0.0, -0.0, 1e-300, -1e-300, 1e-9, kPiOver4, -kPiOver4, std::nextafter(kPiOver4, 0.0)}) {
    double s, c;
    sincos_quarter(x, &s, &c);
    EXPECT_LE(ulps(s, std::sin(x)), kMaxUlps) << x;
    EXPECT_LE(ulps(c, std::cos(x)), kMaxUlps) << x;
    if (x != 0) {
      EXPECT_EQ(std::signbit(s), std::signbit(x)) << x;  // odd function
    }
  }
  double s, c;
  sincos_quarter(0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
}

}  // namespace
}  // namespace tb

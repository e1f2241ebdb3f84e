#include "lib/core/math.h"

#include <gtest/gtest.h>

#include "lib/core/frame.h"
#include "lib/core/rng.h"

namespace tb {
namespace {

TEST(SafeMath, ClampsRoundOffOutsideTheDomain) {
  EXPECT_EQ(safe_sqrt(-1e-17), 0.0);
  EXPECT_EQ(safe_acos(1.0 + 1e-15), 0.0);
  EXPECT_DOUBLE_EQ(safe_acos(-1.0 - 1e-15), kPi);
  EXPECT_DOUBLE_EQ(safe_asin(1.0 + 1e-15), kPiOver2);
}

TEST(SafeMath, DifferenceOfProductsSurvivesCancellation) {
  // a*b - c*d where the naive product loses every significant digit.
  const double a = 1.0 + 0x1p-30, b = 1.0 - 0x1p-30, c = 1.0, d = 1.0;
  EXPECT_EQ(difference_of_products(a, b, c, d), -0x1p-60);
  EXPECT_EQ(sum_of_products(a, b, -c, d), -0x1p-60);
}

TEST(CompensatedSum, ExactOnAdversarialSequence) {
  CompensatedSum s;
  double naive = 0;
  for (int i = 0; i < 1000; ++i) {
    for (double x : {1e16, 1.0, -1e16}) {
      s += x;
      naive += x;
    }
  }
  EXPECT_EQ(s.value(), 1000.0);
  EXPECT_NE(naive, 1000.0);  // documents why the compensated sum exists
}

TEST(Frame, IsOrthonormalAndRoundTrips) {
  Rng rng(9);
  for (int i = 0; i < 10000; ++i) {
    const double z = 2 * rng.uniform() - 1, phi = 2 * kPi * rng.uniform();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    Vec3 n(r * std::cos(phi), r * std::sin(phi), z);
    if (i == 0) n = Vec3(0, 0, -1);  // the branch point of the construction
    const Frame f = Frame::from_z(n);
    EXPECT_NEAR(glm::dot(f.s, f.t), 0.0, 1e-14);
    EXPECT_NEAR(glm::dot(f.s, f.n), 0.0, 1e-14);
    EXPECT_NEAR(glm::length(f.s), 1.0, 1e-14);
    EXPECT_NEAR(glm::length(f.t), 1.0, 1e-14);
    EXPECT_NEAR(glm::dot(glm::cross(f.s, f.t), f.n), 1.0, 1e-14);  // right-handed
    const Vec3 v(0.3, -0.2, 0.7);
    const Vec3 back = f.to_local(f.to_world(v));
    EXPECT_NEAR(glm::length(back - v), 0.0, 1e-14);
  }
}

}  // namespace
}  // namespace tb

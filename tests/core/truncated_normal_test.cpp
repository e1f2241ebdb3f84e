#include "lib/core/truncated_normal.h"

#include <gtest/gtest.h>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>

#include "lib/core/math.h"

namespace tb {
namespace {

struct Case {
  double mu, sigma, a, b;
};

// Includes the lens perturbation's setting (Otsu et al.: theta on [-pi, pi]), means far outside
// the interval on either side (double and long double regimes), tiny and huge sigma.
const Case kCases[] = {
    {0, 0.1, -kPi, kPi},   {0, 1, -kPi, kPi},   {0, 100, -kPi, kPi},  {0, 1, 0.3, 0.9},     {0, 1, 3, 4},
    {0, 1, -4, -3},        {0, 1, 8, 9},        {0, 1, 25, 26},       {0, 1, 45, 46},       {0, 1, -120, -119},
    {0, 1e-3, 0.1, 0.2},   {2, 1e-4, 1.99999, 2.00002}, {0, 1e8, 1, 2},     {1e3, 1e8, 1, 2}, {0, 1, -1e-9, 1e-9},
    {5, 1, -kInfinity, 0}, {-5, 2, 0, kInfinity}, {0, 1, 2, 2.0000001},
};

TEST(TruncatedNormal, RejectsInvalidParameters) {
  EXPECT_FALSE(TruncatedNormal::create(0, 0, 0, 1));
  EXPECT_FALSE(TruncatedNormal::create(0, 1, 1, 1));
  EXPECT_FALSE(TruncatedNormal::create(0, 1, 2, 1));
  EXPECT_FALSE(TruncatedNormal::create(std::nan(""), 1, 0, 1));
  // 1000 standard deviations away: the mass underflows even long double.
  EXPECT_FALSE(TruncatedNormal::create(0, 1e-3, 1, 2));
}

TEST(TruncatedNormal, InverseRoundTrip) {
  for (const Case& c : kCases) {
    const auto t = TruncatedNormal::create(c.mu, c.sigma, c.a, c.b);
    ASSERT_TRUE(t) << c.mu << " " << c.sigma << " " << c.a << " " << c.b;
    double prev = -kInfinity;
    for (int i = 0; i <= 1000; ++i) {
      const double u = std::min(i / 1000.0, kOneMinusEpsilon);
      const double x = t->sample(u);
      ASSERT_GE(x, c.a);
      ASSERT_LE(x, c.b);
      ASSERT_GE(x, prev) << "not monotone at u = " << u;
      prev = x;
      // 1e-9, plus what a few ulps of x = mu + sigma xi cost in u (intrinsic for intervals
      // only a few million doubles wide).
      const double tol = 1e-9 + 8 * t->pdf(x) * kEpsilon * (std::abs(x) + std::abs(c.mu));
      EXPECT_NEAR(t->cdf(x), u, tol) << "mu " << c.mu << " sigma " << c.sigma << " [" << c.a << ", " << c.b
                                      << "] u = " << u << " x = " << x;
    }
  }
}

TEST(TruncatedNormal, PdfIntegratesToOneAndMatchesCdf) {
  using GK = boost::math::quadrature::gauss_kronrod<double, 15>;
  for (const Case& c : kCases) {
    if (!std::isfinite(c.a) || !std::isfinite(c.b)) continue;
    const auto t = TruncatedNormal::create(c.mu, c.sigma, c.a, c.b);
    ASSERT_TRUE(t);
    // The pdf integrated between the quantiles at k/8 must give 1/8: pdf and sampler agree
    // and the pdf is normalised. Pieces of equal mass keep the quadrature well scaled.
    CompensatedSum total;
    for (int k = 0; k < 8; ++k) {
      const double x0 = k == 0 ? c.a : t->sample(k / 8.0), x1 = k == 7 ? c.b : t->sample((k + 1) / 8.0);
      const double piece = GK::integrate([&](double x) { return t->pdf(x); }, x0, x1, 12, 1e-12);
      EXPECT_NEAR(piece, 0.125, 1e-8) << "mu " << c.mu << " sigma " << c.sigma << " [" << c.a << ", " << c.b
                                      << "] piece " << k;
      total += piece;
    }
    EXPECT_NEAR(total.value(), 1.0, 1e-8);
  }
}

TEST(TruncatedNormal, MatchesBoostWhereNaiveFormulaIsAccurate) {
  const auto t = TruncatedNormal::create(1.0, 2.0, -1.0, 4.0);
  ASSERT_TRUE(t);
  const boost::math::normal_distribution<double> n(1.0, 2.0);
  const double z = boost::math::cdf(n, 4.0) - boost::math::cdf(n, -1.0);
  for (double x : {-1.0, 0.0, 1.3, 3.9}) {
    EXPECT_NEAR(t->pdf(x), boost::math::pdf(n, x) / z, 1e-14);
    EXPECT_NEAR(t->cdf(x), (boost::math::cdf(n, x) - boost::math::cdf(n, -1.0)) / z, 1e-14);
  }
  EXPECT_EQ(t->pdf(4.5), 0.0);
}

}  // namespace
}  // namespace tb

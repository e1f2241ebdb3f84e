#include "validate/chi2/pearson_gof.h"

#include <cmath>
#include <vector>

#include "lib/core/rng.h"

#include <gtest/gtest.h>

#include <boost/math/distributions/chi_squared.hpp>

namespace tb {
namespace {

TEST(Chi2Pearson, ExactFitHasPValueOne) {
  const std::vector<double> e = {10, 20, 30, 40};
  const PearsonResult r = pearson_chi2_gof(e, e);
  EXPECT_EQ(r.statistic, 0.0);
  EXPECT_EQ(r.dof, 3);
  EXPECT_DOUBLE_EQ(r.p_value, 1.0);
}

TEST(Chi2Pearson, StatisticAndPValueMatchHandComputation) {
  const std::vector<double> o = {12, 18, 35, 35};
  const std::vector<double> e = {10, 20, 30, 40};
  const PearsonResult r = pearson_chi2_gof(o, e);
  const double stat = 4.0 / 10 + 4.0 / 20 + 25.0 / 30 + 25.0 / 40;
  EXPECT_NEAR(r.statistic, stat, 1e-12);
  EXPECT_EQ(r.dof, 3);
  EXPECT_NEAR(r.p_value, boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<>(3), stat)),
              1e-14);
}

TEST(Chi2Pearson, SmallCellsArePooled) {
  // Cells with E < 5 (1, 2, 3) pool into one cell of E = 6 >= 5: 3 regular + 1 pooled cells.
  const std::vector<double> o = {1, 1, 4, 50, 60, 70};
  const std::vector<double> e = {1, 2, 3, 50, 60, 70};
  const PearsonResult r = pearson_chi2_gof(o, e);
  EXPECT_EQ(r.pooled_cells, 3u);
  EXPECT_EQ(r.cells, 4u);
  EXPECT_EQ(r.dof, 3);
  EXPECT_DOUBLE_EQ(r.pooled_expected, 6.0);
  EXPECT_DOUBLE_EQ(r.pooled_observed, 6.0);
  EXPECT_NEAR(r.statistic, 0.0, 1e-12);
}

TEST(Chi2Pearson, PoolBelowThresholdMergesIntoSmallestRegularCell) {
  const std::vector<double> o = {2, 50, 60};
  const std::vector<double> e = {1, 50, 60};
  const PearsonResult r = pearson_chi2_gof(o, e);
  EXPECT_EQ(r.cells, 2u);  // (pool + 50-cell), 60-cell
  EXPECT_EQ(r.dof, 1);
  EXPECT_NEAR(r.statistic, 1.0 / 51.0, 1e-12);
}

TEST(Chi2Pearson, ObservationInZeroExpectedCellFailsHardAndNamesTheCell) {
  const std::vector<double> o = {10, 1, 10};
  const std::vector<double> e = {10.5, 0, 10.5};
  const PearsonResult r = pearson_chi2_gof(o, e, {}, [](size_t i) { return "bin #" + std::to_string(i); });
  EXPECT_EQ(r.p_value, 0.0);
  EXPECT_TRUE(r.rejects(1e-12));
  EXPECT_EQ(r.zero_expected_cells, 1u);
  EXPECT_EQ(r.first_zero_expected_cell, "bin #1");
  EXPECT_NE(r.message.find("bin #1"), std::string::npos);
}

TEST(Chi2Pearson, ZeroExpectedWithoutObservationsIsIgnored) {
  const std::vector<double> o = {10, 0, 10};
  const std::vector<double> e = {10, 0, 10};
  const PearsonResult r = pearson_chi2_gof(o, e);
  EXPECT_EQ(r.dof, 1);
  EXPECT_DOUBLE_EQ(r.p_value, 1.0);
}


// The stated minimum detectable density error against simulation: multinomial samples from a
// density off by (1 + e) on half of 50 equal cells and (1 - e) on the other half are rejected at
// alpha = 0.01 in 90% of 1000 replicates at e = the stated MDE (within 4 binomial standard
// errors), and (control) at half that e far less often.
double simulated_power(double e, int cells, int n, double alpha, int replicates) {
  int rejected = 0;
  std::vector<double> expected(cells, static_cast<double>(n) / cells), observed(cells);
  for (int r = 0; r < replicates; ++r) {
    Rng rng = Rng::for_sample(7, 0x6d6465, static_cast<uint64_t>(r));
    std::fill(observed.begin(), observed.end(), 0.0);
    for (int i = 0; i < n; ++i) {
      // First half of the cells holds mass (1 + e) / 2, uniform within the half.
      const double u = rng.uniform();
      const int half = cells / 2;
      const int c = u < 0.5 * (1 + e) ? static_cast<int>(rng.uniform() * half)
                                      : half + static_cast<int>(rng.uniform() * (cells - half));
      observed[static_cast<size_t>(std::min(c, cells - 1))] += 1;
    }
    if (pearson_chi2_gof(observed, expected).rejects(alpha)) ++rejected;
  }
  return static_cast<double>(rejected) / replicates;
}

TEST(Chi2Pearson, MinimumDetectableDensityErrorHasItsPower) {
  const int cells = 50, n = 20000, replicates = 1000;
  const double alpha = 0.01;
  const double e = pearson_min_detectable_density_error(cells - 1, n, alpha);
  ASSERT_TRUE(std::isfinite(e));
  EXPECT_NEAR(e * e * n, pearson_detectable_noncentrality(cells - 1, alpha), 1e-9);
  const double power = simulated_power(e, cells, n, alpha, replicates);
  EXPECT_NEAR(power, 0.9, 4 * std::sqrt(0.9 * 0.1 / replicates)) << "e = " << e;
  // Negative control: half the error is not detected at 90% power.
  const double half = simulated_power(e / 2, cells, n, alpha, replicates);
  EXPECT_LT(half, 0.5) << "power at e/2 = " << half;
  EXPECT_TRUE(std::isinf(pearson_min_detectable_density_error(0, n, alpha)));
}

}  // namespace
}  // namespace tb

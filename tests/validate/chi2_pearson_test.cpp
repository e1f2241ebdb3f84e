#include "validate/chi2/pearson_gof.h"

#include <vector>

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

}  // namespace
}  // namespace tb

// Unit tests of regional adaptation (estimators/mcmc/adaptation.h, partition.h, adaptive_chains.h)
// and of the regional adaptive random walk (analytic/mcmc/regional_adaptive_walk.h): the arithmetic
// of Otsu et al.'s Algorithm 1 (Eq. 4-6, the lambda_min clamp), the partitions and their registry,
// the regional densities in the Hastings ratio, and bit-identical parallel chains whatever the
// thread count. The statistical checks are the mcmc.adaptation.* checks of tb check.
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "analytic/mcmc/regional_adaptive_walk.h"
#include "estimators/mcmc/adaptation.h"
#include "estimators/mcmc/adaptive_chains.h"
#include "estimators/mcmc/partition.h"
#include "lib/core/parallel.h"

namespace tb::mcmc {
namespace {

TEST(McmcRegionalAdaptation, DefaultsAreThoseOfOtsuSec81) {
  const AdaptationOptions o;
  EXPECT_EQ(o.lambda0, 1.0);
  EXPECT_EQ(o.batch, 10);
  EXPECT_EQ(o.gamma_max, 1.0);
  EXPECT_EQ(o.gamma_scale, 5.0);
  EXPECT_EQ(o.target_acceptance, 0.5);
  EXPECT_EQ(o.lambda_min, -30.0);
}

// Eq. 6: gamma_j = min(gamma_max, gamma_scale j^{-1/2}).
TEST(McmcRegionalAdaptation, GammaScheduleEq6) {
  const OtsuAdaptation a(1, {});
  EXPECT_EQ(a.gamma(1), 1.0);
  EXPECT_EQ(a.gamma(25), 1.0);
  EXPECT_DOUBLE_EQ(a.gamma(100), 0.5);
  EXPECT_DOUBLE_EQ(a.gamma(10000), 0.05);
}

// Algorithm 1, lines 11-18: one update per L visits of the region, by gamma_j sgn(a_hat - a*);
// the other region is untouched; sigma = exp(lambda / 2).
TEST(McmcRegionalAdaptation, SignUpdateEveryLVisitsPerRegion) {
  OtsuAdaptation a(2, {}, true);
  for (int i = 0; i < 9; ++i) a.observe(0, 0.9);
  EXPECT_EQ(a.lambda(0), 1.0);  // 9 < L visits: no update yet
  a.observe(0, 0.9);            // a_hat = 0.9 > 0.5: lambda += gamma_1 = 1
  EXPECT_EQ(a.lambda(0), 2.0);
  EXPECT_EQ(a.lambda(1), 1.0);
  EXPECT_DOUBLE_EQ(a.sigma(0), std::exp(1.0));
  for (int i = 0; i < 10; ++i) a.observe(1, 0.49);  // a_hat < a*, by a little: still a full step down
  EXPECT_EQ(a.lambda(1), 0.0);
  ASSERT_EQ(a.record().size(), 2u);
  EXPECT_EQ(a.record()[1].region, 1);
  EXPECT_EQ(a.record()[1].j, 1);
  EXPECT_DOUBLE_EQ(a.record()[1].a_hat, 0.49);
}

TEST(McmcRegionalAdaptation, DifferenceUpdateIsTheRobbinsMonroStep) {
  RobbinsMonroAdaptation a(1, {});
  for (int i = 0; i < 10; ++i) a.observe(0, 0.7);
  EXPECT_DOUBLE_EQ(a.lambda(0), 1.0 + 1.0 * (0.7 - 0.5));
}

TEST(McmcRegionalAdaptation, LambdaClampedAtLambdaMin) {
  OtsuAdaptation a(1, {.lambda0 = -29.5});
  for (int i = 0; i < 10; ++i) a.observe(0, 0.0);
  EXPECT_EQ(a.lambda(0), -30.0);
  for (int i = 0; i < 10; ++i) a.observe(0, 0.0);
  EXPECT_EQ(a.lambda(0), -30.0);
}

TEST(McmcPartition, GridCellsCoverSpaceAndRegistryBuildsVariants) {
  const GridPartition<2> g({0.0, 0.0}, {2.0, 3.0}, {2, 3});
  EXPECT_EQ(g.regions(), 6);
  EXPECT_EQ(g.region_of({0.5, 0.5}), 0);
  EXPECT_EQ(g.region_of({1.5, 0.5}), 1);
  EXPECT_EQ(g.region_of({0.5, 2.5}), 4);
  EXPECT_EQ(g.region_of({-7.0, 9.0}), 4);   // outside the box: nearest boundary cell
  EXPECT_EQ(g.region_of({1.999, 2.999}), 5);
  EXPECT_EQ(g.region_of({2.0, 3.0}), 5);
  const PartitionBox<2> box{{0.0, 0.0}, {2.0, 3.0}, {2, 3}};
  EXPECT_EQ(make_partition<2>("grid", box)->regions(), 6);
  EXPECT_EQ(make_partition<2>("global", box)->regions(), 1);
  EXPECT_TRUE(make_partition<2>("global", box)->adapts());
  EXPECT_FALSE(make_partition<2>("fixed", box)->adapts());
  EXPECT_EQ(make_partition<2>("fixed", box)->name(), "fixed");
  // The quadtree is registered in 2d only (the root: one region; its refinement is the driver's).
  EXPECT_EQ(make_partition<2>("quadtree", box)->regions(), 1);
  EXPECT_THROW(make_partition<1>("quadtree", PartitionBox<1>{{0.0}, {1.0}, {1}}), std::invalid_argument);
  EXPECT_THROW(make_partition<2>("octree", box), std::invalid_argument);
}

// T(x -> y) uses sigma(region(x)), T(y -> x) sigma(region(y)): the Hastings ratio carries both.
TEST(McmcRegionalWalk, DensitiesUseTheRegionOfTheirOrigin) {
  const auto part = make_partition<1>("grid", two_scale_box());
  OtsuAdaptation ad(2, {});
  ad.set_lambda(0, std::log(0.25 * 0.25));
  ad.set_lambda(1, std::log(4.0 * 4.0));
  const RegionalAdaptiveWalk<1, RegionPartition<Point<1>>, OtsuAdaptation> walk(part, &ad);
  const Point<1> x{-0.5}, y{1.0};
  EXPECT_DOUBLE_EQ(walk.scale(x), 0.25);
  EXPECT_DOUBLE_EQ(walk.scale(y), 4.0);
  EXPECT_DOUBLE_EQ(walk.density(x, y), normal_pdf(1.0, -0.5, 0.25));
  EXPECT_DOUBLE_EQ(walk.density(y, x), normal_pdf(-0.5, 1.0, 4.0));
  const auto k = regional_adaptive_kernel<1>(two_scale_1d(), part, &ad);
  const auto t = two_scale_1d();
  const double r = t.density(y) * normal_pdf(-0.5, 1.0, 4.0) / (t.density(x) * normal_pdf(1.0, -0.5, 0.25));
  EXPECT_DOUBLE_EQ(k.acceptance(0, x, y), std::min(1.0, r));
}

template <class Update>
std::vector<double> adapt_with_threads(size_t threads, const std::string& partition) {
  const ThreadLimit limit(threads);
  const auto part = make_partition<1>(partition, two_scale_box());
  RegionalAdaptation<Update> ad(part->regions(), {});
  const auto target = two_scale_1d();
  const auto kernel = regional_adaptive_kernel<1>(target, part, &ad);
  std::vector<Point<1>> starts;
  for (int c = 0; c < 8; ++c) starts.push_back({c % 2 ? 5.0 : -2.0});
  SynchronousAdaptiveChains ch(kernel, *part, ad, starts, 7, 11);
  for (int b = 0; b < 400; ++b) ch.run_batch(3);
  std::vector<double> out;
  for (int k = 0; k < part->regions(); ++k) out.push_back(ad.lambda(k));
  for (const auto& x : ch.states()) out.push_back(x[0]);
  return out;
}

// Synchronous batches: lambda and every chain state bit-identical with 1 and 2 threads.
TEST(McmcAdaptiveChains, BitIdenticalWhateverTheThreadCount) {
  const auto a = adapt_with_threads<OtsuSignUpdate>(1, "grid");
  const auto b = adapt_with_threads<OtsuSignUpdate>(2, "grid");
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
  EXPECT_NE(a[0], 1.0);  // it did adapt
  EXPECT_LT(a[0], a[1]); // narrow mode in region 0: a smaller scale than the wide one
  EXPECT_EQ(adapt_with_threads<RobbinsMonroDifferenceUpdate>(1, "global"),
            adapt_with_threads<RobbinsMonroDifferenceUpdate>(2, "global"));
}

TEST(McmcAdaptiveChains, FixedPartitionNeverAdapts) {
  const auto a = adapt_with_threads<OtsuSignUpdate>(2, "fixed");
  EXPECT_EQ(a[0], 1.0);
}

// The walk on R^2 over a 2 x 2 grid: the Mutation runs through MetropolisHastings and the regions
// adapt to different scales where the target's widths differ.
TEST(McmcAdaptiveChains, GridOnR2AdaptsPerCell) {
  const GaussianMixtureTarget<2> t({{0.5, {-2.0, -2.0}, {0.2, 0.2}}, {0.5, {2.0, 2.0}, {1.5, 1.5}}},
                                   GridBins<2>({-4.0, -4.0}, {4.0, 4.0}, 4));
  const auto part = std::make_shared<const GridPartition<2>>(Point<2>{-6.0, -6.0}, Point<2>{6.0, 6.0},
                                                             std::array<int, 2>{2, 2});
  OtsuAdaptation ad(part->regions(), {});
  const auto kernel = regional_adaptive_kernel<2>(t, part, &ad);
  std::vector<Point<2>> starts;
  for (int c = 0; c < 8; ++c) starts.push_back(c % 2 ? Point<2>{2.0, 2.0} : Point<2>{-2.0, -2.0});
  SynchronousAdaptiveChains ch(kernel, *part, ad, starts, 3, 5);
  for (int b = 0; b < 3000; ++b) ch.run_batch(2);
  const auto acc = ch.measure(500);
  EXPECT_LT(ad.lambda(0) + 2.0, ad.lambda(3));  // cell (0,0) narrow, cell (1,1) wide
  EXPECT_NEAR(acc.mean(0), 0.5, 0.06);
  EXPECT_NEAR(acc.mean(3), 0.5, 0.06);
}

}  // namespace
}  // namespace tb::mcmc

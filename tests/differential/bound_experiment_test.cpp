// Unit tests of validate/differential/bound_experiment (the Fig. 3 measurement of Zirr &
// Dachsbacher 2020 behind the differential.bound.* checks): the scene, the two-valued samples the
// binomial form relies on, and the test's p-value.
#include <gtest/gtest.h>

#include <cmath>

#include "validate/differential/bound_broken.h"
#include "validate/differential/bound_experiment.h"

namespace tb::bound {
namespace {

TEST(BoundExperiment, LambertSamplesAreTwoValuedAndRatiosConservativeOrder) {
  const auto world = make_world(BoundScene{});
  RunConfig cfg;
  cfg.k = 2;
  cfg.samples_per_pixel = 4096;
  cfg.grid = 2;
  cfg.key = 0xb0;
  const auto px = run(*world, cfg, ratio_eq21);
  ASSERT_EQ(px.size(), 4u);
  for (const PixelStats& p : px) {
    const UnitStats& u = p.pixel_unit;
    EXPECT_EQ(u.n, 4096);
    ASSERT_GT(u.hits, 0);
    // S = albedo * L_e = 0.5 on every contributing path.
    EXPECT_NEAR(u.s_min, 0.5, 1e-12);
    EXPECT_NEAR(u.s_max, 0.5, 1e-12);
    // s^2 / mean^2 of a two-valued sample: (1 - P) / P * n / (n - 1).
    const double P = static_cast<double>(u.hits) / static_cast<double>(u.n);
    EXPECT_NEAR(u.relative_variance(), (1 - P) / P * 4096.0 / 4095.0, 1e-9 * u.relative_variance());
    int64_t sub_n = 0, sub_hits = 0;
    for (const UnitStats& s : p.sub) {
      sub_n += s.n;
      sub_hits += s.hits;
    }
    EXPECT_EQ(sub_n, u.n);
    EXPECT_EQ(sub_hits, u.hits);
    EXPECT_GE(u.r_min, 1.0);
    EXPECT_LE(u.r_min, u.r_mean());
    EXPECT_LE(u.r_mean(), u.r_max);
  }
  // Eq. 21 dominates the broken copy without p(i_1) by the camera density (thousands here).
  const auto broken = run(*world, cfg, ratio_eq21_without_camera_density);
  for (size_t i = 0; i < px.size(); ++i) {
    EXPECT_EQ(broken[i].pixel_unit.hits, px[i].pixel_unit.hits);  // same stream, same paths
    EXPECT_GT(px[i].pixel_unit.r_min, 100.0 * broken[i].pixel_unit.r_min);
  }
}

TEST(BoundExperiment, ConservativePValueIsTheLowerBinomialTail) {
  UnitStats u;
  u.n = 10;
  u.hits = 1;
  u.r_min = u.r_max = 1.0;  // p0 = 1/2
  u.sum_r = 1.0;
  EXPECT_NEAR(conservative_p_value(u, BoundRule::kMin), 11.0 / 1024.0, 1e-12);  // P(X <= 1)
  u.hits = 10;
  u.sum_r = 10.0;
  EXPECT_NEAR(conservative_p_value(u, BoundRule::kMean), 1.0, 1e-12);
  u.hits = 0;
  EXPECT_EQ(conservative_p_value(u, BoundRule::kMin), 1.0);  // nothing to test
}

}  // namespace
}  // namespace tb::bound

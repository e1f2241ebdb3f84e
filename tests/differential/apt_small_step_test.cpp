// Unit tests of the APT small step (Zirr & Dachsbacher 2020, Sec. 7.1, Listing 1):
// estimators/mcmc/kkt_footprints.h (the KKT loop in closed-form cases) and
// lib/mcmc/apt_small_step.h (the scales of real paths meet the constraint of Eq. 24, the camera's
// sigma, the asymmetry of T, T as the product of its factors).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "estimators/mcmc/kkt_footprints.h"
#include "lib/core/rng.h"
#include "lib/mcmc/apt_small_step.h"
#include "validate/render/render_compare.h"

namespace tb::mcmc {
namespace {

TEST(AptKkt, EqualSharesWhenAllAmplified) {
  const std::vector<double> F = {1.0, 4.0, 0.5};
  const auto r = kkt_amplifiers(F, {true, true, true}, 0.1);
  ASSERT_EQ(r.rounds, 1);
  double sum = 0.0;
  for (size_t j = 0; j < F.size(); ++j) {
    EXPECT_TRUE(r.active[j]);
    EXPECT_DOUBLE_EQ(r.amplifier[j], 3.0 * F[j] / 0.1);  // Eq. 26: A_j = n F_j / R
    sum += F[j] / r.amplifier[j];
  }
  EXPECT_NEAR(sum, 0.1, 1e-15);  // the constraint of Eq. 24
}

TEST(AptKkt, RemovesGroupsThatNeedNoAmplificationAndRepeats) {
  // R = 1, n = 3: target 1/3; F_2 = 0.2 gives A = 0.6 <= 1 and is removed (Listing 1 line 22),
  // budget 0.8 over two: A_0 = 1 / 0.4 = 2.5, A_1 = 2 / 0.4 = 5.
  const auto r = kkt_amplifiers({1.0, 2.0, 0.2}, {true, true, true}, 1.0);
  EXPECT_EQ(r.rounds, 2);
  EXPECT_FALSE(r.active[2]);
  EXPECT_DOUBLE_EQ(r.amplifier[2], 1.0);
  EXPECT_DOUBLE_EQ(r.amplifier[0], 2.5);
  EXPECT_DOUBLE_EQ(r.amplifier[1], 5.0);
  EXPECT_NEAR(1.0 / 2.5 + 2.0 / 5.0 + 0.2, 1.0, 1e-15);
}

TEST(AptKkt, InactiveFromStartTakesNoBudget) {
  const auto r = kkt_amplifiers({1.0, 0.0, 3.0}, {true, false, true}, 0.5);
  EXPECT_EQ(r.rounds, 1);
  EXPECT_DOUBLE_EQ(r.amplifier[1], 1.0);
  EXPECT_DOUBLE_EQ(r.amplifier[0], 2.0 / 0.5);
  EXPECT_DOUBLE_EQ(r.amplifier[2], 6.0 / 0.5);
}

TEST(AptKkt, TwoRemovalsInOnePass) {
  // R = 0.9, target 0.3: F = 0.2 twice gives A = 2/3, both removed, budget 0.5 for the camera alone.
  const auto r = kkt_amplifiers({1.0, 0.2, 0.2}, {true, true, true}, 0.9);
  EXPECT_EQ(r.rounds, 2);
  EXPECT_DOUBLE_EQ(r.amplifier[0], 2.0);
  EXPECT_FALSE(r.active[1]);
  EXPECT_FALSE(r.active[2]);
}

TEST(AptKkt, NoGroupNeedsAmplification) {
  // Every footprint already below its share: all removed, the plain sampler (A = 1) everywhere.
  const auto r = kkt_amplifiers({0.1, 0.1}, {true, true}, 1.0);
  for (size_t j = 0; j < 2; ++j) {
    EXPECT_FALSE(r.active[j]);
    EXPECT_DOUBLE_EQ(r.amplifier[j], 1.0);
  }
}

TEST(AptSmallStep, ScalesMeetConstraintAndTIsAsymmetric) {
  const auto world = load_scene_at_resolution("cornell-box.json", 64, 64);
  const AptTarget target(*world, 3);
  const AptSmallStep step(target);
  const double P = 64.0 * 64.0, R = 1.0 / std::sqrt(P);
  Rng rng = Rng::for_sample(1, 0xa97, 0);
  RngUniforms u(rng);
  AptState x(target.dimension());
  int found = 0, asymmetric = 0;
  for (int tries = 0; tries < 200000 && found < 20; ++tries) {
    for (double& v : x) v = rng.uniform();
    if (!(target.density(x) > 0.0)) continue;
    ++found;
    const AptScales s = target.scales(x);
    ASSERT_TRUE(s.traced);
    ASSERT_EQ(s.sigma.size(), 3u);
    int n = 0;
    double sum = 0.0;
    for (size_t j = 0; j < 3; ++j) {
      EXPECT_NEAR(s.sigma[j], 1.0 / std::sqrt(2.0 * std::numbers::pi * s.kkt.amplifier[j]), 1e-15);
      if (s.kkt.active[j]) {
        ++n;
        sum += s.footprint[j] / s.kkt.amplifier[j];
      } else {
        sum += s.footprint[j];
      }
    }
    EXPECT_NEAR(sum, R, 1e-12 * R);  // Eq. 24's constraint, inactive groups at their plain footprint
    if (s.kkt.active[0]) {
      EXPECT_NEAR(s.kkt.amplifier[0], n / R, 1e-9 * n / R);  // F_0 = 1
    }
    const auto y = step.propose(x, u);
    ASSERT_TRUE(y.has_value());
    double prod = 1.0;
    for (size_t i = 0; i < x.size(); ++i) prod *= AptSmallStep::factor(s, i, (*y)[i] - x[i]);
    const double fwd = step.density(x, *y), rev = step.density(*y, x);
    EXPECT_NEAR(fwd, prod, 1e-12 * prod);
    if (std::abs(fwd - rev) > 1e-6 * std::max(fwd, rev)) ++asymmetric;
  }
  EXPECT_EQ(found, 20);
  EXPECT_GT(asymmetric, 10);  // sigma(y) != sigma(x): the reverse density differs
}

}  // namespace
}  // namespace tb::mcmc

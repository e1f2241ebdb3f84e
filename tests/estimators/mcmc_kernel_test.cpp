// Unit tests of the generic MCMC kernels (estimators/mcmc/) on small analytic targets: acceptance
// formula, state-dependent selection, reversible-jump density convention, multiple-try extended
// balance, expected-value splatting (exact on a finite space) and the Robbins-Monro adapter.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "analytic/mcmc/continuous_proposals.h"
#include "analytic/mcmc/finite_target.h"
#include "analytic/mcmc/gaussian_mixture_target.h"
#include "analytic/mcmc/trans_dimensional_target.h"
#include "estimators/mcmc/adaptation.h"
#include "estimators/mcmc/kernel_step.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/multiple_try.h"
#include "estimators/mcmc/reversible_jump.h"

namespace tb::mcmc {
namespace {

TEST(McmcAcceptance, Conventions) {
  EXPECT_EQ(acceptance_from(0.0, 1.0), 0.0);
  EXPECT_EQ(acceptance_from(1.0, 0.0), 1.0);
  EXPECT_EQ(acceptance_from(1.0, 4.0), 0.25);
  EXPECT_EQ(acceptance_from(4.0, 1.0), 1.0);
  EXPECT_EQ(acceptance_from(std::nan(""), 1.0), 0.0);
}

TEST(McmcMetropolisHastings, AcceptanceMatchesHastingsFormulaWithSelection) {
  FiniteTarget t;
  MetropolisHastings k(t, Mixture(FiniteParitySelection{}, RingStepProposal(64), FiniteIndependentProposal(64)));
  const FiniteParitySelection c;
  const RingStepProposal ring(64);
  for (int x : {0, 1, 7, 63})
    for (int y : {1, 2, 6, 4}) {
      const double num = t.density(y) * c(0, y) * ring.density(y, x);
      const double den = t.density(x) * c(0, x) * ring.density(x, y);
      // A move the component states it cannot make (c T(x -> y) = 0) into a state of positive
      // target is an error of the proposal: never accepted, and reported by decide().
      const double expect = den > 0 ? std::min(1.0, num / den) : 0.0;
      EXPECT_DOUBLE_EQ(k.acceptance(0, x, y), num > 0 ? expect : 0.0) << x << " " << y;
      if (!(c(0, x) * ring.density(x, y) > 0.0) && t.density(y) > 0.0) {
        EXPECT_EQ(decide(k.terms(0, x, y)).status, MoveStatus::kZeroForward) << x << " " << y;
      }
    }
}

TEST(McmcMixture, SelectionFrequenciesMatchSelectionProbabilities) {
  FiniteTarget t;
  MetropolisHastings k(t, Mixture(FiniteParitySelection{}, RingStepProposal(64), FiniteIndependentProposal(64)));
  Rng rng(3);
  RngUniforms u(rng);
  int n1 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) n1 += k.sample_move(1, u)->component == 1;  // c_1(odd) = 0.6
  EXPECT_NEAR(static_cast<double>(n1) / n, 0.6, 5 * std::sqrt(0.24 / n));
}

// Expected-value splatting is exactly unbiased at stationarity: sum_x pi(x) E[(1-a) f(x) + a f(y)]
// = (pi P) f = pi f, computed exactly on the finite space.
TEST(McmcSplat, ExpectedValueIsExactOnFiniteSpace) {
  FiniteTarget t;
  MetropolisHastings k(t, Mixture(FiniteParitySelection{}, RingStepProposal(64), FiniteIndependentProposal(64)));
  auto f = [](int i) { return std::sin(0.3 * i) + 0.01 * i * i; };
  double lhs = 0.0, rhs = 0.0;
  for (int x = 0; x < 64; ++x) {
    rhs += t.probability(x) * f(x);
    for (int c = 0; c < 2; ++c)
      for (int y = 0; y < 64; ++y) {
        const double q = k.proposal_density(c, x, y);
        if (q == 0.0) continue;
        Transition<int, decltype(k)::Move> tr;
        tr.current = x;
        tr.proposed = y;
        tr.acceptance = k.acceptance(c, x, y);
        double s = 0.0;
        splat_expected(tr, [&](int z, double w) { s += w * f(z); });
        lhs += t.probability(x) * q * s;
      }
  }
  EXPECT_NEAR(lhs, rhs, 1e-12);
}

TEST(McmcStep, DeterministicForSeed) {
  auto t = bimodal_1d();
  MetropolisHastings k(t, SingleProposal(GaussianRandomWalk<1>(1.0)));
  auto run = [&] {
    Rng rng = Rng::for_sample(5, 6, 7);
    RngUniforms u(rng);
    Point<1> x{0.0};
    for (int i = 0; i < 100; ++i) x = step(k, x, u).next();
    return x[0];
  };
  EXPECT_EQ(run(), run());
}

TEST(McmcReversibleJump, DensityConventionGivesGreensRatio) {
  const CubicSplitMap g;
  const BirthDeath bd(g);
  const TransDimState x = Point<1>{0.3};
  const double a = 0.7;
  const TransDimState y = g.up(std::get<Point<1>>(x), a);
  EXPECT_NEAR(bd.density(x, y), normal_pdf(a, 0, 1) / (2.0 + 1.5 * a * a), 1e-12);
  EXPECT_EQ(bd.density(y, x), 1.0);
  Rng rng(1);
  RngUniforms u(rng);
  const auto back = bd.propose(y, u);
  ASSERT_TRUE(back);
  EXPECT_NEAR(std::get<Point<1>>(*back)[0], 0.3, 1e-14);
}

TEST(McmcMultipleTry, ExtendedBalanceOnSeededMoves) {
  auto t = bimodal_1d();
  MultipleTry k(t, GaussianRandomWalk<1>(2.0), 4);
  for (uint64_t i = 0; i < 200; ++i) {
    Rng rng = Rng::for_sample(1, 2, i);
    RngUniforms u(rng);
    const Point<1> x = t.sample_exact(u);
    const auto m = k.sample_move(x, u);
    ASSERT_TRUE(m);
    const auto y = k.destination(*m);
    const auto r = k.reverse(x, *m);
    EXPECT_EQ(k.destination(r)[0], x[0]);
    const double f = t.density(x) * k.move_density(x, *m) * k.acceptance(x, *m);
    const double b = t.density(y) * k.move_density(y, r) * k.acceptance(y, r);
    EXPECT_NEAR(f, b, 1e-10 * std::max(f, b));
  }
}

// The Robbins-Monro adapter drives the acceptance of a random walk on N(0, 1) towards a* = 0.44.
TEST(McmcAdaptation, RobbinsMonroReachesTargetAcceptance) {
  GaussianMixtureTarget<1> t({{1.0, {0.0}, {1.0}}}, GridBins<1>({-3.0}, {3.0}, 6));
  RobbinsMonroScale ad(1, 0.05, {.target_acceptance = 0.44, .batch = 50, .gamma_max = 1.0, .gamma_scale = 2.0});
  MetropolisHastings k(t, SingleProposal(GaussianRandomWalk<1>(ad.parameter(0))));
  Rng rng(9);
  RngUniforms u(rng);
  Point<1> x{0.0};
  for (int i = 0; i < 200000; ++i) {
    const auto tr = step(k, x, u);
    ad.observe(0, tr.acceptance);
    x = tr.next();
    k = MetropolisHastings(t, SingleProposal(GaussianRandomWalk<1>(ad.parameter(0))));
  }
  EXPECT_GT(ad.updates(0), 3000);
  EXPECT_LT(ad.gamma(ad.updates(0)), 0.05);  // diminishing adaptation
  // Acceptance with the final scale, measured on a fresh run.
  double acc = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const auto tr = step(k, x, u);
    acc += tr.acceptance;
    x = tr.next();
  }
  EXPECT_NEAR(acc / n, 0.44, 0.02);
  EXPECT_GT(ad.parameter(0), 1.5);  // the optimal 1D scale is about 2.4 (Gelman, Roberts & Gilks 1996)
}

}  // namespace
}  // namespace tb::mcmc

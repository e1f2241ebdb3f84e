// Unit tests of the MCMC targets and proposals (analytic/mcmc/): bin masses sum to one, exact
// draws follow the bin masses (chi-square, alpha = 1e-6 per target), proposals sample what their
// density states (chi-square of 1D proposals), the banana's x1 marginal, the cubic map round trip.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "analytic/mcmc/banana_target.h"
#include "analytic/mcmc/continuous_proposals.h"
#include "analytic/mcmc/finite_target.h"
#include "analytic/mcmc/gaussian_mixture_target.h"
#include "analytic/mcmc/hole_target.h"
#include "analytic/mcmc/trans_dimensional_target.h"
#include "validate/chi2/pearson_gof.h"
#include "validate/mcmc/proposal_chi2.h"

namespace tb::mcmc {
namespace {

template <class T>
void expect_exact_draws_match_bins(const T& t, int n, uint64_t key) {
  double total = 0.0;
  std::vector<double> obs(t.bin_count(), 0.0), ex(t.bin_count());
  for (int i = 0; i < t.bin_count(); ++i) total += ex[i] = t.bin_mass(i);
  EXPECT_NEAR(total, 1.0, 1e-12);
  for (double& e : ex) e *= n;
  for (int i = 0; i < n; ++i) {
    Rng rng = Rng::for_sample(1, key, i);
    RngUniforms u(rng);
    const auto x = t.sample_exact(u);
    EXPECT_GT(t.density(x), 0.0);
    obs[t.bin_of(x)] += 1.0;
  }
  const auto r = pearson_chi2_gof(obs, ex);
  EXPECT_GT(r.p_value, 1e-6) << r.message;
}

TEST(McmcTargets, ExactDrawsMatchBinMasses) {
  expect_exact_draws_match_bins(bimodal_1d(), 100000, 1);
  expect_exact_draws_match_bins(trimodal_2d(), 100000, 2);
  expect_exact_draws_match_bins(BananaTarget(), 100000, 3);
  expect_exact_draws_match_bins(HoleTarget(), 100000, 4);
  expect_exact_draws_match_bins(FiniteTarget(), 100000, 5);
  expect_exact_draws_match_bins(TransDimensionalTarget(), 100000, 6);
}

TEST(McmcTargets, DensitiesAgreeWithNormalisation) {
  // Midpoint quadrature of the 1D mixture: integral of density = scale (3.7).
  const auto t = bimodal_1d();
  double s = 0.0;
  const double h = 1e-3;
  for (double x = -15.0; x < 15.0; x += h) s += t.density({x + 0.5 * h}) * h;
  EXPECT_NEAR(s, t.normalization(), 1e-9);
  // Banana marginal of x1 by quadrature over x2.
  const BananaTarget b;
  for (double x1 : {-1.0, 0.3, 2.0}) {
    double m = 0.0;
    for (double x2 = -20.0; x2 < 20.0; x2 += h) m += b.density({x1, x2 + 0.5 * h}) * h;
    EXPECT_NEAR(m, b.marginal_x1_pdf(x1), 1e-9);
  }
  // The hole is empty.
  EXPECT_EQ(HoleTarget(1.2).density({0.5, 0.5}), 0.0);
}

TEST(McmcTargets, TransDimensionalModelProbabilities) {
  const TransDimensionalTarget t;
  double p1 = 0.0;
  for (int i = 0; i < t.bin_count(); ++i)
    if (i < 15) p1 += t.bin_mass(i);
  EXPECT_NEAR(p1, t.model_probability(1), 1e-12);
}

TEST(McmcTargets, CubicMapRoundTrip) {
  const CubicSplitMap g;
  for (double x : {-2.0, 0.0, 0.4, 3.0})
    for (double a : {-3.0, -0.2, 0.0, 1e-9, 0.5, 2.5}) {
      const auto [xb, ab] = g.down(g.up({x}, a));
      EXPECT_NEAR(xb[0], x, 1e-12);
      EXPECT_NEAR(ab, a, 1e-12);
    }
}

// Proposals sample what they state: chi-square of y ~ T(x -> .) against the stated density
// (validate/mcmc/proposal_chi2.h, 101 cells over [-30, 30]), alpha = 1e-6 per proposal.
template <class P>
double proposal_chi2_p(const P& p, Point<1> x, int n) {
  return check_proposal_chi2_1d(p, x, -30.0, 30.0, n, 77, 1).p_value();
}

TEST(McmcProposals, SampleTheirStatedDensity) {
  EXPECT_GT(proposal_chi2_p(GaussianRandomWalk<1>(1.3), {0.5}, 100000), 1e-6);
  EXPECT_GT(proposal_chi2_p(IndependentGaussian<1>({0.5}, 3.0), {2.0}, 100000), 1e-6);
  EXPECT_GT(proposal_chi2_p(RegionalRandomWalk<1>({0.0}, {0.5, 2.0}), {1.0}, 100000), 1e-6);
  // Negative control: a stated sigma 5% off is rejected by this chi-square.
  const auto broken = StatedDensity(IndependentGaussian<1>({0.5}, 3.0), IndependentGaussian<1>({0.5}, 3.15));
  EXPECT_LT(proposal_chi2_p(broken, {2.0}, 100000), 1e-6);
}

TEST(McmcProposals, FiniteProposalsSumToOne) {
  const RingStepProposal ring(64);
  const FiniteIndependentProposal ind(64);
  for (int i : {0, 5, 63}) {
    double s1 = 0.0, s2 = 0.0;
    for (int j = 0; j < 64; ++j) {
      s1 += ring.density(i, j);
      s2 += ind.density(i, j);
    }
    EXPECT_NEAR(s1, 1.0, 1e-15);
    EXPECT_NEAR(s2, 1.0, 1e-12);
  }
}

}  // namespace
}  // namespace tb::mcmc

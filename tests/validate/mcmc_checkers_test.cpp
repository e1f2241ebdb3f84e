// Tests of the MCMC checkers (validate/mcmc/): each accepts a correct kernel and rejects the broken
// variants it is meant to see; the blind spots of the pairwise check (a density misstated
// consistently) are asserted too, so a change in what it sees is noticed. Sizes are small: the
// registered checks (validate/checks/mcmc_checks.cpp) run the full protocol.
#include <gtest/gtest.h>

#include "validate/mcmc/chain_diagnostics.h"
#include "validate/mcmc/exact_balance.h"
#include "validate/mcmc/flux_symmetry.h"
#include "validate/mcmc/kernels.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/rj_jacobian.h"
#include "validate/mcmc/stationarity.h"

namespace tb::mcmc {
namespace {

constexpr double kAlpha = 1e-5;

TEST(McmcExactBalance, CorrectKernelsPass) {
  for (const auto& r : {check_exact_balance(kernels::finite_ring(), 64), check_exact_balance(kernels::finite_independent(), 64),
                        check_exact_balance(kernels::finite_mixture(), 64)}) {
    EXPECT_TRUE(r.passed) << r.message;
    EXPECT_LT(r.max_balance_residual, 1e-15);
  }
}

TEST(McmcExactBalance, MissingProposalRatioIsRejected) {
  const auto r = check_exact_balance(kernels::finite_mixture_no_ratio(), 64);
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_GT(r.max_balance_residual, 1e-4);
}

template <class K>
PairwiseBalanceResult pairwise(const K& k, int64_t n = 2000) {
  return check_pairwise_balance<K>(k, [&](Uniforms& u) { return k.target().sample_exact(u); }, n, 1, 2);
}

TEST(McmcPairwise, CorrectKernelsPass) {
  EXPECT_TRUE(pairwise(kernels::gm1d_mixture()).passed);
  EXPECT_TRUE(pairwise(kernels::gm1d_mtm()).passed);
  EXPECT_TRUE(pairwise(kernels::banana_regional()).passed);
  EXPECT_TRUE(pairwise(kernels::transdim_rj()).passed);
  EXPECT_TRUE(pairwise(kernels::hole_rw()).passed);
}

TEST(McmcPairwise, MissingProposalRatioIsRejected) {
  const auto r = pairwise(kernels::gm1d_mixture_no_ratio());
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_FALSE(pairwise(kernels::banana_regional_no_ratio()).passed);
}

// By construction the pairwise check sees only whether the acceptance agrees with the STATED
// density: a consistently misstated density or Jacobian is invisible to it.
TEST(McmcPairwise, BlindToConsistentlyMisstatedDensities) {
  EXPECT_TRUE(pairwise(kernels::gm1d_misstated_sigma()).passed);
  EXPECT_TRUE(pairwise(kernels::transdim_rj_no_jacobian()).passed);
}

TEST(McmcRjJacobian, CorrectMapPassesBrokenMapFails) {
  auto low = [](Uniforms& u) { return Point<1>{4.0 * u.next() - 2.0}; };
  const auto good = check_rj_jacobian<CubicSplitMap>(CubicSplitMap{}, low, 200, 1, 2);
  EXPECT_TRUE(good.passed) << good.message;
  const auto bad = check_rj_jacobian<WithoutJacobian<CubicSplitMap>>(WithoutJacobian(CubicSplitMap{}), low, 200, 1, 2);
  EXPECT_FALSE(bad.passed) << bad.message;
}

TEST(McmcStationarity, AcceptsCorrectRejectsBroken) {
  const auto good = check_stationarity_chi2(kernels::gm1d_mixture(), bimodal_1d(), 20000, 20, 3, 4, kAlpha);
  EXPECT_TRUE(good.passed) << good.message;
  const auto bad = check_stationarity_chi2(kernels::gm1d_mixture_no_ratio(), bimodal_1d(), 20000, 20, 3, 4, kAlpha);
  EXPECT_FALSE(bad.passed) << bad.message;
  const auto rj = check_stationarity_chi2(kernels::transdim_rj_no_jacobian(), TransDimensionalTarget(), 20000, 20, 3, 4,
                                          kAlpha);
  EXPECT_FALSE(rj.passed) << rj.message;
}

TEST(McmcStationarity, HoleEntryFailsOutright) {
  // A "kernel" that ignores pi (always accepts) walks into the hole: zero-mass bin observed.
  struct AlwaysAccept {
    double operator()(double, double, double, double) const { return 1.0; }
  };
  const MetropolisHastings k(HoleTarget(), SingleProposal(GaussianRandomWalk<2>(1.0)), AlwaysAccept{});
  const auto r = check_stationarity_chi2(k, HoleTarget(), 2000, 5, 1, 1, kAlpha);
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.pearson.zero_expected_observed, 0.0);
}

TEST(McmcFlux, AcceptsCorrectRejectsBroken) {
  const auto good = check_flux_symmetry(kernels::finite_mixture(), FiniteTarget(), 1000, 100, 5, 6, kAlpha);
  EXPECT_TRUE(good.passed) << good.message;
  const auto bad = check_flux_symmetry(kernels::finite_mixture_no_ratio(), FiniteTarget(), 1000, 100, 5, 6, kAlpha);
  EXPECT_FALSE(bad.passed) << bad.message;
}

TEST(McmcRank, AcceptsCorrectRejectsBroken) {
  const auto good = check_gandy_scott_rank(kernels::gm1d_mixture(), bimodal_1d(), 10000, 10, 7, 8, kAlpha);
  EXPECT_TRUE(good.passed) << good.message;
  const auto bad = check_gandy_scott_rank(kernels::gm1d_mixture_no_ratio(), bimodal_1d(), 10000, 10, 7, 8, kAlpha);
  EXPECT_FALSE(bad.passed) << bad.message;
}

TEST(McmcDiagnostics, ReportsRhatAndEss) {
  const auto d = chain_diagnostics(kernels::gm1d_independent(), bimodal_1d(), 4, 4000, 1, 2);
  EXPECT_LT(d.split_rhat, 1.01) << d.message;
  EXPECT_GT(d.ess, 1000.0) << d.message;
  EXPECT_GT(d.mean_acceptance, 0.2);
}

}  // namespace
}  // namespace tb::mcmc

// The (target, kernel) combinations the MCMC checks and tests run, named once so that checks,
// tests and docs agree. Each factory returns a kernel by value.
#pragma once

#include "analytic/mcmc/banana_target.h"
#include "analytic/mcmc/continuous_proposals.h"
#include "analytic/mcmc/finite_target.h"
#include "analytic/mcmc/gaussian_mixture_target.h"
#include "analytic/mcmc/hole_target.h"
#include "analytic/mcmc/prefix_target.h"
#include "analytic/mcmc/trans_dimensional_target.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/multiple_try.h"
#include "estimators/mcmc/reversible_jump.h"
#include "validate/mcmc/broken_variants.h"

namespace tb::mcmc::kernels {

inline auto finite_ring() { return MetropolisHastings(FiniteTarget(), SingleProposal(RingStepProposal(64))); }
inline auto finite_independent() {
  return MetropolisHastings(FiniteTarget(), SingleProposal(FiniteIndependentProposal(64)));
}
inline auto finite_mixture() {
  return MetropolisHastings(FiniteTarget(),
                            Mixture(FiniteParitySelection{}, RingStepProposal(64), FiniteIndependentProposal(64)));
}
inline auto finite_mixture_no_ratio() {
  return MetropolisHastings(FiniteTarget(),
                            Mixture(FiniteParitySelection{}, RingStepProposal(64), FiniteIndependentProposal(64)),
                            MetropolisRatioOnly{});
}

inline auto gm1d_rw() { return MetropolisHastings(bimodal_1d(), SingleProposal(GaussianRandomWalk<1>(2.5))); }
inline auto gm1d_mixture() {
  return MetropolisHastings(bimodal_1d(), Mixture(DistanceSelection{}, GaussianRandomWalk<1>(0.8),
                                                  IndependentGaussian<1>({0.5}, 3.0)));
}
inline auto gm1d_mixture_no_ratio() {
  return MetropolisHastings(
      bimodal_1d(), Mixture(DistanceSelection{}, GaussianRandomWalk<1>(0.8), IndependentGaussian<1>({0.5}, 3.0)),
      MetropolisRatioOnly{});
}
inline auto gm1d_independent() {
  return MetropolisHastings(bimodal_1d(), SingleProposal(IndependentGaussian<1>({0.5}, 2.0)));
}
inline auto gm1d_misstated_sigma() {
  return MetropolisHastings(bimodal_1d(), SingleProposal(misstated_independent_gaussian<1>({0.5}, 2.0)));
}
inline auto gm1d_mtm() { return MultipleTry(bimodal_1d(), GaussianRandomWalk<1>(2.0), 4); }

inline auto gm2d_rw() { return MetropolisHastings(trimodal_2d(), SingleProposal(GaussianRandomWalk<2>(1.6))); }
inline auto gm2d_mtm() { return MultipleTry(trimodal_2d(), GaussianRandomWalk<2>(1.8), 5); }

inline auto banana_rw() { return MetropolisHastings(BananaTarget(), SingleProposal(GaussianRandomWalk<2>(0.7))); }
// State-dependent scale (Otsu et al., Eq. 2): three regions along x1.
inline auto banana_regional() {
  return MetropolisHastings(BananaTarget(),
                            SingleProposal(RegionalRandomWalk<2>({-1.0, 1.0}, {0.9, 0.35, 0.9})));
}
inline auto banana_regional_no_ratio() {
  return MetropolisHastings(BananaTarget(), SingleProposal(RegionalRandomWalk<2>({-1.0, 1.0}, {0.9, 0.35, 0.9})),
                            MetropolisRatioOnly{});
}

inline auto hole_rw() { return MetropolisHastings(HoleTarget(), SingleProposal(GaussianRandomWalk<2>(1.0))); }

inline auto transdim_rj() {
  return MetropolisHastings(TransDimensionalTarget(),
                            Mixture(ModelSelection{}, BirthDeath(CubicSplitMap{}), ModelwiseRandomWalk(0.9)));
}
inline auto transdim_rj_no_jacobian() {
  return MetropolisHastings(TransDimensionalTarget(), Mixture(ModelSelection{}, BirthDeath(WithoutJacobian(CubicSplitMap{})),
                                                              ModelwiseRandomWalk(0.9)));
}

// The multiple-try large step over the prefixes of one draw (Zirr & Dachsbacher 2020, Sec. 7.2),
// and its broken variant without the reverse candidates.
inline auto prefix_mtm() { return PrefixMultipleTry(PrefixTarget{}); }
inline auto prefix_mtm_without_reverse() { return WithoutReverseCandidates(PrefixMultipleTry(PrefixTarget{})); }

}  // namespace tb::mcmc::kernels

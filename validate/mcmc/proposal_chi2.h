// Chi-square of a 1D proposal T(x -> .) at a fixed x against its own STATED density
// (docs/validation.md A, "mutation proposals"), through the generic sampler test of
// validate/chi2/sampler_chi2.h (101 cells, expected counts by adaptive quadrature of the stated
// density). This is the check that sees a density stated inconsistently with the sampler (a wrong
// sigma), which the pairwise balance check cannot see by construction.
#pragma once

#include <cstdint>
#include <optional>

#include "analytic/mcmc/normal.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/checker_concepts.h"

namespace tb::mcmc {

template <Proposal P>
  requires std::same_as<typename P::State, Point<1>>
SamplerChi2Result check_proposal_chi2_1d(const P& p, Point<1> x, double lo, double hi, int64_t samples, uint64_t seed,
                                         uint64_t key) {
  const auto sample = [&](Uniforms& u) -> std::optional<double> {
    const auto y = p.propose(x, u);
    if (!y) return std::nullopt;
    return (*y)[0];
  };
  const auto pdf = [&](double y) { return p.density(x, Point<1>{y}); };
  SamplerChi2Options o;
  o.samples = samples;
  o.seed = seed;
  o.key = key;
  return chi2_test(Chi2Domain::interval(lo, hi, 101), sample, pdf, o);
}

}  // namespace tb::mcmc

// The checks every registered mutation gets without an edit: each mutation of a registry (PSS:
// pss_mutations(); path space: path_mutations()) alone, run by the renderer's own kernel, under
// the pairwise detailed-balance checker (pi T a symmetric to 1e-9 on seeded pairs) and, in path
// space, under flux symmetry by bins (the check that sees a stated T inconsistent with the
// sampler, which the pairwise check cannot see when it compares the stated T with itself). A
// mutation registered later, by a researcher or a test, is picked up by the registered checks
// mcmc.pss.cornell.registered_mutations.pairwise, mcmc.pss.cornell.registered_mutations.chi2 (the
// proposal chi-square of each mutation against its stated density), mlt.path_space.
// registered_mutations.pairwise, mlt.path_space.registered_mutations.flux_bins and
// mlt.path_space.registered_mutations.chi2 (through the projection each path-space mutation
// declares, validate/mcmc/path_space/path_projections.h), which call
// these functions.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/pss/pss_mutation.h"
#include "validate/registry.h"

namespace tb {

// Longest path (in bounces) of the registered-mutation checks' scenes.
inline constexpr int kRegisteredCheckMaxDepth = 3;

// PSS: the 16 x 16 Cornell box, PSSMLT over the path tracer (max depth 3), Y_ref = mean of pi
// over 4096 uniform states (so a rescaled step spans its sigma range); pairs from uniform starts
// preferring pi > 0. Details per mutation under "mutations".
// wrap (negative controls only): replaces each registered mutation by a broken variant of it
// before it is checked (return the argument to leave it as it is).
using PssMutationWrap = std::function<std::shared_ptr<const pss::PssMutation>(std::shared_ptr<const pss::PssMutation>)>;
CheckResult pss_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name,
                                              const PssMutationWrap& wrap = {});

// PSS, proposal chi-square (docs/validation.md A, "mutation proposals"; docs/mlt-pss.md): each
// registered mutation alone, proposed by the renderer's kernel (begin, then the lazy coordinates
// read through PssState), at three states of the target above (the dimmest, median and brightest
// of 64 uniform states with pi > 0, so a rescaled step is tested at different sigma(x)); the
// marginal of coordinate 0 (camera stream, read by every state) and of coordinate 1 (the light
// stream's first uniform, never read by the path tracer) against the marginal the mutation STATES.
// Assumption, checked numerically per test: with the move's reads and scales held fixed, the
// stated T factorises in coordinate i, i.e. log T(x, y[i <- v]) - log T(x, y[i <- v0]) is the
// same for 8 proposed backgrounds y (to 1e-9 relative, 16 proposed values v). The marginal is then
// that 1D factor, normalised over the circle by adaptive Gauss-Kronrod quadrature, given that the
// rest of T integrates over the other coordinates to a constant that does not depend on y_i (not
// checked: for the registered mutations it is a product of normalised 1D densities in read
// order, pss_state.h; were it not, the chi-square would reject rather than pass). A test whose T
// does not factorise fails the check (reported as such, "DOES NOT FACTORISE"). Histogram: the wrapped displacement
// y_i - x_i in 101 cells of a window from 512 pilot proposals (their range widened by its span on
// each side; the whole circle if that covers most of it), mass outside as the failure cell.
// Samples 4e4 per test (quick), 2e5 (full); fixed seeds from ctx.seed and the name; Šidák over
// all (mutation, state, coordinate) tests at family alpha 1e-3. Details per mutation under
// "mutations" ("rejected": some test of it rejected), "every_mutation_rejected" for controls.
CheckResult pss_registered_mutations_chi2(const CheckContext& ctx, const std::string& name,
                                          const PssMutationWrap& wrap = {});

// Path space: the 16 x 16 Cornell box (max depth 3), BDPT start paths; each mutation's acceptance
// against its reference density (reference_density_of: the independent assembly for Veach's
// four, the mutation's stated density for any other). Details per mutation by name.
// wrap (negative controls only) gets the context of the scene the mutation is checked on.
using PathMutationWrap = std::function<std::shared_ptr<const path_space::PathMutation>(
    std::shared_ptr<const path_space::PathMutation>, const PathContext&)>;
CheckResult path_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name,
                                               const PathMutationWrap& wrap = {});

// Path space, flux symmetry by bins (validate/mcmc/path_space/flux_bins.h): each registered
// mutation alone (its selection c(x) = [applies to x], so moves to paths it does not apply to are
// rejected), chains from importance-resampled BDPT starts on the 16 x 16 Cornell box (max depth 3),
// bins of 4 x 4 pixels x path length, a binomial test per bin pair with >= 20 crossings, Šidák over
// the pairs and then over the mutations, alpha = 1e-5. A mutation with no bin pair tested on the
// Cornell box is run on the glossy, caustic, dg-mirror-chain and dg-glass scenes in turn; one with none
// tested anywhere fails the check (nothing tested). The record's statistic is the family p, so a
// negative control is caught only by a rejection (statistic < alpha), not by a pair left untested.
CheckResult path_registered_mutations_flux_bins(const CheckContext& ctx, const std::string& name,
                                                const PathMutationWrap& wrap = {});

// Path space, proposal chi-square (docs/validation.md A, "mutation proposals"; docs/mlt-path-space.md):
// every registered mutation (path_mutations()) through the 2D projection declared for it by name
// (validate/mcmc/path_space/path_projections.h): on each scene of its declaration (16 x 16), test
// paths from seeded BDPT samples (max depth 4), at each the declared configurations; y proposed by
// the mutation (or its wrapper) mapped to the chart, against the chart density stated from its
// density(x, y) (validate/chi2: expected counts by adaptive quadrature or, where the projection
// asks for it, a Monte Carlo integral with its variance in the statistic; failed proposals and the
// stated mass off the chart in one cell). Šidák over every (mutation, configuration) test at family
// alpha 1e-5; fixed seeds from ctx.seed, the name, the mutation and the scene. A registered mutation
// with no declared projection FAILS the check (named in the message); one declared without a
// projection (no_projection_reason) is listed with its reason and not tested; one whose
// declaration yields no configuration on any of its scenes fails (nothing tested). Details per
// mutation under "mutations" ("status": tested, exempt, no projection, nothing tested, error;
// "rejected": some test of it rejected), "every_tested_rejected" for controls.
CheckResult path_registered_mutations_chi2(const CheckContext& ctx, const std::string& name,
                                           const PathMutationWrap& wrap = {});

}  // namespace tb

// The checks every registered mutation gets without an edit: each mutation of a registry (PSS:
// pss_mutations(); path space: path_mutations()) alone, run by the renderer's own kernel, under
// the pairwise detailed-balance checker (pi T a symmetric to 1e-9 on seeded pairs) and, in path
// space, under flux symmetry by bins (the check that sees a stated T inconsistent with the
// sampler, which the pairwise check cannot see when it compares the stated T with itself). A
// mutation registered later, by a researcher or a test, is picked up by the registered checks
// mcmc.pss.cornell.registered_mutations.pairwise, mlt.path_space.registered_mutations.pairwise and
// mlt.path_space.registered_mutations.flux_bins, which call these functions.
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

}  // namespace tb

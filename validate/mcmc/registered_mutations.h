// The checks every registered mutation gets without an edit: each mutation of a registry (PSS:
// pss_mutations(); path space: path_mutations()) alone, run by the renderer's own kernel, under
// the pairwise detailed-balance checker (pi T a symmetric to 1e-9 on seeded pairs). A mutation
// registered later, by a researcher or a test, is picked up by the registered checks
// mcmc.pss.cornell.registered_mutations.pairwise and mlt.path_space.registered_mutations.pairwise,
// which call these functions.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/pss/pss_mutation.h"
#include "validate/registry.h"

namespace tb {

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
using PathMutationWrap = std::function<std::shared_ptr<const path_space::PathMutation>(
    std::shared_ptr<const path_space::PathMutation>)>;
CheckResult path_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name,
                                               const PathMutationWrap& wrap = {});

}  // namespace tb

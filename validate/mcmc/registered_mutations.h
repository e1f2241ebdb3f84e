// The checks every registered mutation gets without an edit: each mutation of a registry (PSS:
// pss_mutations(); path space: path_mutations()) alone, run by the renderer's own kernel, under
// the pairwise detailed-balance checker (pi T a symmetric to 1e-9 on seeded pairs). A mutation
// registered later, by a researcher or a test, is picked up by the registered checks
// mcmc.pss.cornell.registered_mutations.pairwise and mlt.path_space.registered_mutations.pairwise,
// which call these functions.
#pragma once

#include <string>

#include "validate/registry.h"

namespace tb {

// PSS: the 16 x 16 Cornell box, PSSMLT over the path tracer (max depth 3), Y_ref = mean of pi
// over 4096 uniform states (so a rescaled step spans its sigma range); pairs from uniform starts
// preferring pi > 0. Details per mutation under "mutations".
CheckResult pss_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name);

// Path space: the 16 x 16 Cornell box (max depth 3), BDPT start paths; each mutation's acceptance
// against its reference density (reference_density_of: the independent assembly for Veach's
// four, the mutation's stated density for any other). Details per mutation by name.
CheckResult path_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name);

}  // namespace tb

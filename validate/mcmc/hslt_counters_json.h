// The walk statistics of a half-vector or manifold mutation (HsltCounters, the Table 3 statistics of
// Kaplanyan et al. 2014) as check details, for validate/checks/mcmc_hslt_checks.cpp and
// mcmc_memlt_checks.cpp.
#pragma once

#include <nlohmann/json.hpp>

#include "lib/mcmc/path_space/hslt_mutation.h"

namespace tb::path_space {

inline nlohmann::json counters_json(const HsltCounters& c) {
  const HsltCountsSnapshot s = snapshot(c);
  nlohmann::json status = nlohmann::json::object();
  for (int i = 0; i < kHsltWalkStatusCount; ++i)
    status[hslt_walk_status_name(static_cast<HsltWalkStatus>(i))] = s.status[static_cast<size_t>(i)];
  return {{"proposals", s.proposals},
          {"forward_walks", status},
          {"iterations_per_converged_walk", s.iterations_per_converged()},
          {"iterations_per_walk", s.iterations_per_walk()},
          {"non_reversible", s.non_reversible},
          {"non_reversible_fraction_of_converged", s.non_reversible_fraction()},
          {"generated", s.generated},
          {"jumps", {{"attempted", s.jump_attempted}, {"projected", s.jump_projected}, {"succeeded", s.jump_succeeded}}}};
}

}  // namespace tb::path_space

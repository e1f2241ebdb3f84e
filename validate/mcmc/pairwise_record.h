// The check record of a pairwise detailed-balance run (pairwise_balance.h), shared by every
// registered pairwise check: the statistic, the counts and a reproducer of the worst pair.
#pragma once

#include <string>

#include <fmt/format.h>

#include "validate/check_result.h"
#include "validate/mcmc/pairwise_balance.h"

namespace tb {

// `name`: the string the pairs' key was hashed from (hash_string(name)).
inline CheckResult pairwise_record(const mcmc::PairwiseBalanceResult& r, const std::string& name) {
  CheckResult res;
  res.passed = r.passed;
  res.statistic_name = "max relative |F - B|";
  res.statistic = r.max_rel_residual;
  res.samples = r.pairs;
  res.message = r.message;
  res.details = {{"live_pairs", r.live},
                 {"violations", r.violations},
                 {"worst_index", r.worst_index},
                 {"failed_proposals", r.failed_proposals},
                 {"nonfinite", r.nonfinite},
                 {"zero_forward", r.zero_forward},
                 {"tolerance", r.tolerance},
                 {"reproducer", fmt::format("Rng::for_sample(seed, hash_string(\"{}\"), {})", name, r.worst_index)}};
  return res;
}

}  // namespace tb

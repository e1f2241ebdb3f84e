// The record every registered check produces (ARCHITECTURE.md: "the registry of named checks
// that tb check runs"; docs/validation.md: stated alpha, sample counts, seed, reproducer).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "validate/plot_spec.h"

namespace tb {

struct CheckResult {
  bool passed = false;
  std::string statistic_name;   // e.g. "t", "chi2", "max rel. error", "alpha_hat"
  double statistic = 0.0;
  double p_value = -1.0;        // < 0 when the check is deterministic (no p-value)
  double alpha = 0.0;           // significance level after multiple-comparison correction
  int64_t samples = 0;          // total samples (or configurations) the check used
  std::string message;          // one line a user reads first: what was found
  // Power: the smallest effect the check rejects with 90% power at its alpha and sample size
  // (docs/statistics.md, "What a passing check rules out"), relative (0.02 = 2%); infinite when
  // the check has not stated it, or has no power. effect_kind says which effect ("uniform relative
  // bias of the image", "relative bias of the estimate", ...).
  double min_detectable_effect = std::numeric_limits<double>::infinity();
  std::string effect_kind;
  nlohmann::json details = nlohmann::json::object();  // everything else (per-case p-values, ...)
  std::vector<PlotSpec> plots;

  // Filled by the runner:
  std::string name;
  uint64_t seed = 0;
  double seconds = 0.0;
  std::string reproducer;
};

void to_json(nlohmann::json& j, const CheckResult& r);

}  // namespace tb

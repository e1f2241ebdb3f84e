// Settings shared by every integrator run, and the per-run statistics they report.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace tb {

// What an MCMC integrator reports of its run (`tb render` prints it and writes it to the JSON
// record next to the image): per mutation type, proposals and acceptances.
struct MutationReport {
  std::string name;
  int64_t proposed = 0;
  int64_t accepted = 0;
  int64_t errors = 0;  // proposed moves with a stated forward density of 0 or non-finite Hastings terms
  double acceptance() const { return proposed > 0 ? static_cast<double>(accepted) / static_cast<double>(proposed) : 0.0; }
};
struct RunReport {
  std::vector<MutationReport> mutations;
  int64_t mutations_total = 0;
  double mutations_per_second = 0.0;
  double startup_seconds = 0.0;  // path-space MLT: its chains' start-ups, summed over chains (0: not reported)
};

struct RenderSettings {
  int64_t spp = 16;          // samples per pixel in total
  int64_t passes = 8;        // Welch samples per pixel: spp is split evenly over the passes
  int max_depth = 10;        // maximum number of scattering events (path length in segments - 1)
  uint64_t seed = 1;
  double time_budget_s = 0;  // > 0: stop after the pass during which the budget ran out
  // The range of passes (MLT: chains) this call renders: [first_pass, first_pass + pass_count),
  // pass_count < 0: to the last. Results do not depend on how a run is cut into ranges.
  int64_t first_pass = 0;
  int64_t pass_count = -1;
  bool russian_roulette = true;
  int rr_min_depth = 3;      // roulette starts after this many scattering events
  // Restrict bidirectional estimators to one path length (segments) / one technique (s, t):
  // used by the per-technique checks. -1: all.
  int only_length = -1;
  int only_s = -1;           // with only_s >= 0 the single technique is unweighted (weight 1)
  // Integrator parameters by name (`tb render --param NAME=VALUE`); each integrator lists the
  // names it takes (IntegratorInfo::parameters) and ignores nothing: the program rejects a name
  // the integrator does not list. Empty: the integrator's defaults.
  std::map<std::string, double> params;
  std::function<void(double)> progress = [](double) {};
  const std::atomic<bool>* interrupted = nullptr;  // stop between passes
  RunReport* report = nullptr;  // filled by MCMC integrators when set
};

}  // namespace tb

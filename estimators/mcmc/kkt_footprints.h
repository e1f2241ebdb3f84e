// The constrained optimisation of Zirr & Dachsbacher 2020, Sec. 7.1.1-7.1.2 (Eq. 23-26), in the
// derivative-free form of Eq. 21, as printed in their Listing 1, lines 13-26: given per-dimension
// footprints F_j (the area each dimension's plain sampling density spreads the endpoint over, in
// the units of the camera dimension's footprint) and a budget R, find amplifiers A_j of the
// sampling density such that sum_{active j} F_j / A_j + sum_{inactive j} F_j = R with equal shares
// F_j / A_j = R_active / n (the KKT stationarity condition, Eq. 25: each s_j reciprocal to its
// coefficient, Eq. 26) and A_j > 1 for every active j (the inequality s_j <= 1; complementary
// slackness removes a dimension that would need A_j <= 1 and subtracts its unamplified footprint
// from the budget, then the optimisation is repeated, Listing 1 lines 22-26). Inactive dimensions
// (and those the caller marks inactive from the start, e.g. Dirac vertices, Listing 1 line 14) keep
// A_j = 1 (Listing 1 line 31). Generic: nothing here knows about paths.
#pragma once

#include <cstddef>
#include <vector>

namespace tb::mcmc {

struct KktAmplifiers {
  std::vector<double> amplifier;  // A_j (1 for inactive dimensions)
  std::vector<bool> active;
  int rounds = 0;                 // passes of the do-while loop
};

// footprints[j] >= 0; active[j] false for dimensions excluded from the start; budget = R (Listing 1
// line 13 in footprint units). The loop follows Listing 1 exactly: within one pass the share
// target = budget / count(active) is that of the pass's start.
inline KktAmplifiers kkt_amplifiers(const std::vector<double>& footprints, std::vector<bool> active, double budget) {
  KktAmplifiers out;
  const size_t n = footprints.size();
  out.amplifier.assign(n, 1.0);
  bool retry = true;
  while (retry) {
    ++out.rounds;
    retry = false;
    size_t count = 0;
    for (size_t j = 0; j < n; ++j) count += active[j] ? 1 : 0;
    if (count == 0) break;
    const double target = budget / static_cast<double>(count);  // line 17
    for (size_t j = 0; j < n; ++j) {
      if (!active[j]) continue;
      out.amplifier[j] = footprints[j] / target;  // line 21
      if (!(out.amplifier[j] > 1.0)) {            // line 22: the inequality A_j > 1 (s_j <= 1)
        active[j] = false;
        budget -= footprints[j];
        retry = true;
      }
    }
  }
  for (size_t j = 0; j < n; ++j)
    if (!active[j]) out.amplifier[j] = 1.0;  // line 31
  out.active = std::move(active);
  return out;
}

}  // namespace tb::mcmc

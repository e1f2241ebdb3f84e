// Broken variants of the APT small step (lib/mcmc/apt_small_step.h) for the negative controls of
// validate/checks/mcmc_apt_checks.cpp. Wrappers only: nothing here is in lib/.
#pragma once

#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/concepts.h"
#include "lib/mcmc/apt_small_step.h"

namespace tb::mcmc {

// The kernel K with its acceptance formed under the symmetric assumption: T(x -> y) in place of
// T(y -> x) (reverse term := forward term, so a = min{1, f(y) / f(x)}), as if the proposal were
// symmetric. The proposal and its stated density are K's. For the APT step, whose scales depend on
// the state, this breaks detailed balance; the pairwise check must see it.
template <MoveKernel K>
class ForwardDensityBothWays {
 public:
  using State = typename K::State;
  using Move = typename K::Move;
  explicit ForwardDensityBothWays(K k) : k_(std::move(k)) {}
  const auto& target() const { return k_.target(); }
  double target_density(const State& x) const { return k_.target_density(x); }
  std::optional<Move> sample_move(const State& x, Uniforms& u) const { return k_.sample_move(x, u); }
  decltype(auto) destination(const Move& m) const { return k_.destination(m); }
  Move reverse(const State& x, const Move& m) const { return k_.reverse(x, m); }
  double move_density(const State& x, const Move& m) const { return k_.move_density(x, m); }
  MoveTerms move_terms(const State& x, const Move& m) const {
    MoveTerms t = k_.move_terms(x, m);
    t.reverse = t.forward;
    return t;
  }
  double acceptance(const State& x, const Move& m) const { return decide(move_terms(x, m)).acceptance; }

 private:
  K k_;
};

// The APT step's per-coordinate factor stated with every sigma `stated_factor` times too wide
// (the sampler unchanged): the proposal chi-square must reject it.
struct MisstatedAptFactor {
  double stated_factor = 1.05;
  double operator()(const AptScales& s, size_t i, double d) const {
    AptScales w = s;
    for (double& v : w.sigma) v *= stated_factor;
    return AptSmallStep::factor(w, i, d);
  }
};

// The apt integrator (lib/mcmc/apt_integrator.h) splatting without the (1 - a) splat of the
// current state (AptSettings::splat_weight).
inline double apt_splat_without_rejected(Which which, double w, double pi) { return which == Which::kCurrent ? 0.0 : w / pi; }

// The apt integrator's bootstrap weight of a draw from its full-length candidate only, not the sum
// S over its candidates (AptSettings::bootstrap_sum): a path tracer that forgets that every prefix
// is a candidate; b then misses the shorter paths.
inline double apt_bootstrap_last_candidate(const std::vector<double>& w) { return w.empty() ? 0.0 : w.back(); }

}  // namespace tb::mcmc

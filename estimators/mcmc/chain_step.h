// The one Metropolis-Hastings step of the project (Metropolis et al. 1953; Hastings 1970; with
// state-dependent selection, Otsu et al., Sec. 3.2): choose a component, propose, accept or reject,
// splat expected values (Veach 1997, Sec. 11.5). Every MCMC renderer driver (pssmlt, pssmlt-pt,
// pssmlt-pt-rescaled, mmlt, msmlt, msmlt-mmlt, mlt, apt) and every checker that runs a chain
// (flux, stationarity, rank; kernel_step.h's step() runs this function) go through chain_step, and
// every acceptance probability of the project, the pairwise checker's included, is formed by
// decide() below.
//
// The step works on a *scored chain*: the current state x with its cached target pi(x) and whatever
// its splat needs, and a slot for the proposed state y, scored once when proposed. pi is therefore
// evaluated once per proposed state, never again for the acceptance.
//
// Measures: MoveTerms holds pi(x), c_k(x) T_k(x -> y), pi(y) and c_k(y) T_k(y -> x), densities in
// the reference measure of the state space the chain states (any positive factor common to the
// forward and the reverse term may be dropped, e.g. a symmetric T).
#pragma once

#include <cmath>
#include <concepts>
#include <cstdint>

#include "estimators/mcmc/acceptance.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

// The four numbers a Hastings ratio is made of.
struct MoveTerms {
  double pi_x = 0.0;     // pi(x)
  double forward = 0.0;  // c_k(x) T_k(x -> y)
  double pi_y = 0.0;     // pi(y)
  double reverse = 0.0;  // c_k(y) T_k(y -> x)
};

enum class MoveStatus : uint8_t {
  kEvaluated,    // a proposed move, acceptance from the rule
  kNoProposal,   // no component applies, or the proposal failed: the chain stays
  kZeroForward,  // a proposed move whose stated forward density is 0 into a state of positive
                 // target: the proposal sampled where it says it cannot; an error, counted
  kNonFinite,    // a NaN or infinite term: an error, counted, never accepted
};

struct Decision {
  double acceptance = 0.0;
  MoveStatus status = MoveStatus::kNoProposal;
  bool error() const { return status == MoveStatus::kZeroForward || status == MoveStatus::kNonFinite; }
};

// The acceptance probability of a proposed move by `rule` (HastingsRatio: min(1, pi(y) c_k(y)
// T_k(y -> x) / (pi(x) c_k(x) T_k(x -> y)))). A stated forward density of 0 for a move that was
// made into a state of positive target is an error (status kZeroForward, acceptance 0): accepting
// it with certainty, as min(1, r / 0) would, hides a proposal whose density is misstated.
template <class Rule = HastingsRatio>
Decision decide(const MoveTerms& m, const Rule& rule = {}) {
  if (!std::isfinite(m.pi_x) || !std::isfinite(m.pi_y) || !std::isfinite(m.forward) || !std::isfinite(m.reverse))
    return {0.0, MoveStatus::kNonFinite};
  if (m.pi_y > 0.0 && !(m.forward > 0.0)) return {0.0, MoveStatus::kZeroForward};
  return {rule(m.pi_x, m.forward, m.pi_y, m.reverse), MoveStatus::kEvaluated};
}

// A chain the step can run: the current state (scored), one proposal slot (scored by propose), and
// the terms of the Hastings ratio for the move in the slot. `select(u)` maps one uniform to a
// component (c_k(x) by inversion, -1 when none applies); `propose(k, u)` fills the slot from the
// current state with component k (false: the proposal failed); accept() makes the slot current;
// reject() discards it.
template <class C>
concept ScoredChain = requires(C& c, int k, double v, Uniforms& u) {
  { c.select(v) } -> std::convertible_to<int>;
  { c.propose(k, u) } -> std::convertible_to<bool>;
  { c.terms(k) } -> std::convertible_to<MoveTerms>;
  { c.accept() };
  { c.reject() };
};

// What one step did.
struct StepOutcome {
  int component = -1;
  double acceptance = 0.0;
  bool accepted = false;
  MoveStatus status = MoveStatus::kNoProposal;
};

// Which state a splat is of.
enum class Which : uint8_t { kCurrent, kProposed };

// One transition: `decisions` gives the selection uniform before the proposal and the acceptance
// uniform after it (always drawn, so the number of decision uniforms per step never depends on
// failure); `proposal_uniforms` feeds the proposal (it may be the same stream). splat(which, weight)
// receives the expected-value weights: (kCurrent, 1 - a) and (kProposed, a), or (kCurrent, 1) when
// nothing was proposed; a zero weight is never passed.
template <class Rule = HastingsRatio, ScoredChain C, class Splat>
StepOutcome chain_step(C& chain, Uniforms& decisions, Uniforms& proposal_uniforms, Splat&& splat,
                       const Rule& rule = {}) {
  StepOutcome out;
  out.component = chain.select(decisions.next());
  const bool proposed = out.component >= 0 && chain.propose(out.component, proposal_uniforms);
  Decision d;
  if (proposed) d = decide(chain.terms(out.component), rule);
  const double ua = decisions.next();
  out.acceptance = d.acceptance;
  out.status = d.status;
  if (!proposed) {
    splat(Which::kCurrent, 1.0);
    if (out.component >= 0) chain.reject();
    return out;
  }
  if (d.acceptance < 1.0) splat(Which::kCurrent, 1.0 - d.acceptance);
  if (d.acceptance > 0.0) splat(Which::kProposed, d.acceptance);
  out.accepted = ua < d.acceptance;
  if (out.accepted)
    chain.accept();
  else
    chain.reject();
  return out;
}

// Per-component counts of a run of steps, for `tb render`'s report and the checkers.
struct ComponentCounts {
  int64_t proposed = 0;  // times selected
  int64_t failed = 0;    // proposals that returned nothing
  int64_t accepted = 0;
  int64_t errors = 0;    // kZeroForward or kNonFinite decisions
  double acceptance_sum = 0.0;
  void add(const StepOutcome& o) {
    ++proposed;
    failed += o.status == MoveStatus::kNoProposal;
    accepted += o.accepted;
    errors += o.status == MoveStatus::kZeroForward || o.status == MoveStatus::kNonFinite;
    acceptance_sum += o.acceptance;
  }
  void merge(const ComponentCounts& o) {
    proposed += o.proposed;
    failed += o.failed;
    accepted += o.accepted;
    errors += o.errors;
    acceptance_sum += o.acceptance_sum;
  }
};

}  // namespace tb::mcmc

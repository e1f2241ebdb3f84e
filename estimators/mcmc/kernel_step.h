// One Metropolis-Hastings transition of any MoveKernel, and expected-value splatting: the
// proposed and the current state both contribute, weighted by a and 1 - a (Veach 1997, Ch. 11, the
// "expected values" optimisation): unbiased for E_pi[f], a Rao-Blackwellisation of splatting the next state.
#pragma once

#include <optional>

#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <class State, class Move>
struct Transition {
  State current{};
  std::optional<Move> move;       // empty when the proposal failed (the chain stays)
  std::optional<State> proposed;  // destination of move
  double acceptance = 0.0;        // a(x -> y); 0 when the proposal failed
  bool accepted = false;
  const State& next() const { return accepted ? *proposed : current; }
};

// Proposes from x, accepts with probability a(x -> y) using one more uniform.
template <MoveKernel K>
Transition<typename K::State, typename K::Move> step(const K& kernel, const typename K::State& x, Uniforms& u) {
  Transition<typename K::State, typename K::Move> t;
  t.current = x;
  t.move = kernel.sample_move(x, u);
  if (t.move) {
    t.proposed = kernel.destination(*t.move);
    t.acceptance = kernel.acceptance(x, *t.move);
  }
  const double ua = u.next();  // always drawn: the number of uniforms per step does not depend on failure
  t.accepted = t.move && ua < t.acceptance;
  return t;
}

// Expected-value splatting: splat(state, weight) is called with (x, 1 - a) and (y, a).
template <class State, class Move, class F>
void splat_expected(const Transition<State, Move>& t, F&& splat) {
  if (!t.proposed) {
    splat(t.current, 1.0);
    return;
  }
  if (t.acceptance < 1.0) splat(t.current, 1.0 - t.acceptance);
  if (t.acceptance > 0.0) splat(*t.proposed, t.acceptance);
}

}  // namespace tb::mcmc

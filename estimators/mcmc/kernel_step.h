// One Metropolis-Hastings transition of any MoveKernel, run by the one step of chain_step.h, and
// expected-value splatting: the proposed and the current state both contribute, weighted by a and
// 1 - a (Veach 1997, Ch. 11, the "expected values" optimisation): unbiased for E_pi[f], a
// Rao-Blackwellisation of splatting the next state.
#pragma once

#include <optional>
#include <utility>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <class State, class Move>
struct Transition {
  State current{};
  std::optional<Move> move;       // empty when the proposal failed (the chain stays)
  std::optional<State> proposed;  // destination of move
  double acceptance = 0.0;        // a(x -> y); 0 when the proposal failed
  bool accepted = false;
  MoveStatus status = MoveStatus::kNoProposal;
  const State& next() const { return accepted ? *proposed : current; }
};

namespace detail {

// Returns `first`, then continues with `rest`: the stream a kernel's sample_move would have read
// had the step not taken its first uniform as the selection uniform.
class PrependedUniforms final : public Uniforms {
 public:
  PrependedUniforms(double first, Uniforms& rest) : first_(first), rest_(&rest) {}
  double next() override {
    if (pending_) {
      pending_ = false;
      return first_;
    }
    return rest_->next();
  }

 private:
  double first_;
  Uniforms* rest_;
  bool pending_ = true;
};

// A MoveKernel seen as a ScoredChain: one "component" (the kernel selects inside sample_move).
template <MoveKernel K>
struct KernelChain {
  using State = typename K::State;
  using Move = typename K::Move;
  const K* kernel;
  Transition<State, Move>* t;
  double select_uniform = 0.0;
  int select(double v) {
    select_uniform = v;
    return 0;
  }
  bool propose(int, Uniforms& u) {
    PrependedUniforms pu(select_uniform, u);
    t->move = kernel->sample_move(t->current, pu);
    if (!t->move) return false;
    t->proposed = kernel->destination(*t->move);
    return true;
  }
  MoveTerms terms(int) const { return kernel->move_terms(t->current, *t->move); }
  void accept() {}
  void reject() {}
};

}  // namespace detail

// Proposes from x, accepts with probability a(x -> y) using one more uniform (chain_step).
template <MoveKernel K>
Transition<typename K::State, typename K::Move> step(const K& kernel, const typename K::State& x, Uniforms& u) {
  Transition<typename K::State, typename K::Move> t;
  t.current = x;
  detail::KernelChain<K> chain{&kernel, &t};
  const auto none = [](Which, double) {};
  StepOutcome o;
  if constexpr (requires { kernel.rule(); })
    o = chain_step(chain, u, u, none, kernel.rule());  // the kernel's rule (negative controls swap it)
  else
    o = chain_step(chain, u, u, none);
  t.acceptance = o.acceptance;
  t.accepted = o.accepted;
  t.status = o.status;
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

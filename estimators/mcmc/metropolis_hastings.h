// The Metropolis-Hastings kernel over a mixture of proposals with state-dependent selection
// (Otsu et al., Sec. 3.2). It exposes, as functions of (x, y), the proposal density
// c_k(x) T_k(x -> y) and the acceptance a_k(x -> y), so that checkers evaluate
// pi(x) c_k(x) T_k(x -> y) a_k(x -> y) without sampling; and it is a MoveKernel (concepts.h), so
// the generic step() of kernel_step.h runs it.
//
// Detailed balance holds per component: pi(x) c_k(x) T_k(x->y) a_k(x->y) is symmetric in (x, y)
// for every k, hence the whole kernel sum_k c_k T_k a_k is reversible with respect to pi.
#pragma once

#include <optional>
#include <utility>

#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/concepts.h"
#include "estimators/mcmc/proposal_mixture.h"

namespace tb::mcmc {

// The Hastings terms of a move x -> y by component k of a mixture, given pi(x) and pi(y):
// {pi(x), c_k(x) T_k(x -> y), pi(y), c_k(y) T_k(y -> x)}. When pi(y) = 0 the move is rejected
// whatever T, so the densities are not evaluated (forward stands at 1). Every kernel over a
// ProposalMixture forms its terms here: MetropolisHastings below and the path-space MLT driver.
// c_x, c_y: c_k(x) and c_k(y) when the caller has them (a chain caches its state's selection);
// negative: computed here.
template <ProposalMixture M>
MoveTerms mixture_terms(const M& mix, int k, const typename M::State& x, const typename M::State& y, double pi_x,
                        double pi_y, double c_x = -1.0, double c_y = -1.0) {
  if (!(pi_y > 0.0)) return {pi_x, 1.0, pi_y, 0.0};
  const double cx = c_x >= 0.0 ? c_x : mix.selection(k, x), cy = c_y >= 0.0 ? c_y : mix.selection(k, y);
  return {pi_x, cx > 0.0 ? cx * mix.density(k, x, y) : 0.0, pi_y, cy > 0.0 ? cy * mix.density(k, y, x) : 0.0};
}

template <Target Tg, ProposalMixture M, class Rule = HastingsRatio>
  requires std::same_as<typename Tg::State, typename M::State>
class MetropolisHastings {
 public:
  using State = typename M::State;
  struct Move {
    int component = 0;
    State y{};
  };

  MetropolisHastings(Tg target, M mixture, Rule rule = {})
      : target_(std::move(target)), mix_(std::move(mixture)), rule_(std::move(rule)) {}

  const Tg& target() const { return target_; }
  const M& mixture() const { return mix_; }
  M& mixture() { return mix_; }
  int components() const { return mix_.components(); }

  // c_k(x) T_k(x -> y): the density of proposing y from x with component k (measure of the state
  // space; for a reversible-jump component, the convention of reversible_jump.h).
  double proposal_density(int k, const State& x, const State& y) const {
    const double c = mix_.selection(k, x);
    return c > 0.0 ? c * mix_.density(k, x, y) : 0.0;
  }
  // The terms of the Hastings ratio of a move by component k (chain_step.h).
  MoveTerms terms(int k, const State& x, const State& y) const {
    return mixture_terms(mix_, k, x, y, target_.density(x), target_.density(y));
  }
  // a_k(x -> y) by the kernel's rule (HastingsRatio: Otsu et al., Sec. 3.2), through decide() as
  // every acceptance of the project.
  double acceptance(int k, const State& x, const State& y) const { return decide(terms(k, x, y), rule_).acceptance; }
  const Rule& rule() const { return rule_; }

  // ---- MoveKernel ------------------------------------------------------------------------------
  double target_density(const State& x) const { return target_.density(x); }
  // One uniform picks the component, the proposal takes what it needs.
  std::optional<Move> sample_move(const State& x, Uniforms& u) const {
    const int k = select_component(mix_, x, u.next());
    if (k < 0) return std::nullopt;
    std::optional<State> y = mix_.propose(k, x, u);
    if (!y) return std::nullopt;
    return Move{k, std::move(*y)};
  }
  const State& destination(const Move& m) const { return m.y; }
  Move reverse(const State& x, const Move& m) const { return Move{m.component, x}; }
  double move_density(const State& x, const Move& m) const { return proposal_density(m.component, x, m.y); }
  MoveTerms move_terms(const State& x, const Move& m) const { return terms(m.component, x, m.y); }
  double acceptance(const State& x, const Move& m) const { return acceptance(m.component, x, m.y); }

 private:
  Tg target_;
  M mix_;
  Rule rule_;
};

}  // namespace tb::mcmc

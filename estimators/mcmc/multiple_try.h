// Multiple-try Metropolis (Liu, Liang & Wong 2000, "The multiple-try method and local
// optimization in Metropolis sampling", JASA 95(449), Sec. 2) with the weight
// w(y, x) = pi(y) T(y -> x) (their lambda = 1):
//   1. draw K tries y_1..y_K ~ T(x -> .), select y = y_J with probability w(y_J, x) / sum_j w(y_j, x);
//   2. draw K - 1 references x*_1..x*_{K-1} ~ T(y -> .), set x*_K = x;
//   3. accept with min(1, sum_j w(y_j, x) / sum_i w(x*_i, y)).
// As a MoveKernel the move holds the tries and the references, move_density is the joint density
// of all of them and of the selection, and reverse() swaps their roles; detailed balance then holds
// on the extended space (Liu et al. 2000, proof of Theorem 1), which the pairwise checker tests.
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <Target Tg, Proposal P>
  requires std::same_as<typename Tg::State, typename P::State>
class MultipleTry {
 public:
  using State = typename P::State;
  struct Move {
    std::vector<State> tries;  // K tries from x
    int selected = 0;          // J: the destination is tries[J]
    std::vector<State> refs;   // K - 1 references from the destination (x*_K = x is implicit)
  };

  MultipleTry(Tg target, P proposal, int tries) : target_(std::move(target)), p_(std::move(proposal)), k_(tries) {}
  int tries() const { return k_; }
  const Tg& target() const { return target_; }

  // w(y, x) = pi(y) T(y -> x)
  double weight(const State& y, const State& x) const { return target_.density(y) * p_.density(y, x); }

  double target_density(const State& x) const { return target_.density(x); }

  std::optional<Move> sample_move(const State& x, Uniforms& u) const {
    Move m;
    m.tries.reserve(k_);
    double sum = 0.0;
    std::vector<double> w(k_);
    for (int j = 0; j < k_; ++j) {
      std::optional<State> y = p_.propose(x, u);
      if (!y) return std::nullopt;  // documented: proposals for MTM are expected not to fail
      w[j] = weight(*y, x);
      sum += w[j];
      m.tries.push_back(std::move(*y));
    }
    const double us = u.next() * sum;
    if (!(sum > 0.0)) return std::nullopt;  // no try has positive weight: stay
    double acc = 0.0;
    m.selected = k_ - 1;
    for (int j = 0; j < k_; ++j) {
      acc += w[j];
      if (us < acc && w[j] > 0.0) {
        m.selected = j;
        break;
      }
    }
    while (!(w[m.selected] > 0.0)) --m.selected;  // rounding fell past the last positive weight
    const State& y = m.tries[m.selected];
    for (int i = 0; i + 1 < k_; ++i) {
      std::optional<State> r = p_.propose(y, u);
      if (!r) return std::nullopt;
      m.refs.push_back(std::move(*r));
    }
    return m;
  }

  const State& destination(const Move& m) const { return m.tries[m.selected]; }

  Move reverse(const State& x, const Move& m) const {
    Move r;
    r.selected = m.selected;
    r.tries.reserve(k_);
    for (int i = 0, j = 0; i < k_; ++i) r.tries.push_back(i == m.selected ? x : m.refs[j++]);
    for (int j = 0; j < k_; ++j)
      if (j != m.selected) r.refs.push_back(m.tries[j]);
    return r;
  }

  // prod_j T(x -> y_j) * w(y_J, x) / sum_j w(y_j, x) * prod_i T(y -> x*_i)
  double move_density(const State& x, const Move& m) const {
    const State& y = destination(m);
    double d = 1.0, sum = 0.0;
    for (const State& t : m.tries) {
      d *= p_.density(x, t);
      sum += weight(t, x);
    }
    if (!(sum > 0.0)) return 0.0;
    d *= weight(y, x) / sum;
    for (const State& r : m.refs) d *= p_.density(y, r);
    return d;
  }

  // The generalised ratio sum_j w(y_j, x) / sum_i w(x*_i, y) as Hastings terms (pi folded into w).
  MoveTerms move_terms(const State& x, const Move& m) const {
    const State& y = destination(m);
    double num = 0.0, den = weight(x, y);
    for (const State& t : m.tries) num += weight(t, x);
    for (const State& r : m.refs) den += weight(r, y);
    return {1.0, den, 1.0, num};
  }
  double acceptance(const State& x, const Move& m) const { return decide(move_terms(x, m)).acceptance; }

 private:
  Tg target_;
  P p_;
  int k_;
};

}  // namespace tb::mcmc

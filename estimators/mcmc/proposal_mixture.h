// Mixtures of proposals with state-dependent selection probabilities c_k(x) (Otsu et al., Sec. 3.2:
// a strategy j is chosen with the "suitability" s(j | x); the acceptance then contains
// s(j | y) / s(j | x)). SingleProposal wraps one Proposal as a one-component mixture; Mixture holds
// several proposals of different types and a selection rule.
#pragma once

#include <cstddef>
#include <optional>
#include <tuple>
#include <type_traits>
#include <utility>

#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <Proposal P>
class SingleProposal {
 public:
  using State = typename P::State;
  explicit SingleProposal(P p) : p_(std::move(p)) {}
  int components() const { return 1; }
  double selection(int, const State&) const { return 1.0; }
  std::optional<State> propose(int, const State& x, Uniforms& u) const { return p_.propose(x, u); }
  double density(int, const State& x, const State& y) const { return p_.density(x, y); }
  const P& proposal() const { return p_; }

 private:
  P p_;
};

// Selection is a callable double(int k, const State& x) returning c_k(x); the c_k(x) must sum to
// one over k for every x (a component with c_k(x) = 0 is never chosen at x).
template <class Selection, Proposal P0, Proposal... P>
class Mixture {
 public:
  using State = typename P0::State;
  static_assert((std::is_same_v<State, typename P::State> && ...), "all components share one state type");

  Mixture(Selection sel, P0 p0, P... p) : sel_(std::move(sel)), parts_(std::move(p0), std::move(p)...) {}

  int components() const { return static_cast<int>(1 + sizeof...(P)); }
  double selection(int k, const State& x) const { return sel_(k, x); }
  std::optional<State> propose(int k, const State& x, Uniforms& u) const {
    return visit(k, [&](const auto& p) { return p.propose(x, u); });
  }
  double density(int k, const State& x, const State& y) const {
    return visit(k, [&](const auto& p) { return static_cast<double>(p.density(x, y)); });
  }
  template <size_t I>
  const auto& component() const {
    return std::get<I>(parts_);
  }

 private:
  template <class F>
  auto visit(int k, F&& f) const {
    return visit_impl(k, f, std::make_index_sequence<1 + sizeof...(P)>{});
  }
  template <class F, size_t... I>
  auto visit_impl(int k, F& f, std::index_sequence<I...>) const {
    using R = decltype(f(std::get<0>(parts_)));
    R r{};
    (void)((static_cast<int>(I) == k ? (r = f(std::get<I>(parts_)), true) : false) || ...);
    return r;
  }

  Selection sel_;
  std::tuple<P0, P...> parts_;
};

// Picks component k with probability c_k(x) from one uniform (inversion of the running sum).
template <ProposalMixture M>
int select_component(const M& m, const typename M::State& x, double u) {
  const int n = m.components();
  double acc = 0.0;
  int last_positive = -1;
  for (int k = 0; k < n; ++k) {
    const double c = m.selection(k, x);
    if (c > 0.0) last_positive = k;
    acc += c;
    if (u < acc && c > 0.0) return k;
  }
  return last_positive;  // rounding: the sum fell just below u
}

}  // namespace tb::mcmc

// The concepts every MCMC estimator in estimators/mcmc/ is written against (ARCHITECTURE.md, "The
// one idea"): a target pi(x), a proposal T(x -> y), a mixture of proposals chosen with state-
// dependent probabilities c_k(x), a dimension-matching map for reversible jump, and a kernel seen
// as "moves" whose forward and reverse fluxes the checkers in validate/mcmc/ compare.
//
// Measures. pi and T are densities with respect to one reference measure on the state space, which
// each implementation states: Lebesgue on R^n for continuous targets, counting measure on finite
// spaces, and for trans-dimensional spaces the disjoint union of Lebesgue measures of each model.
// A dimension-changing move states T with respect to that same union measure, which is where the
// Jacobian of the dimension-matching map enters (Green 1995; see reversible_jump.h).
#pragma once

#include <concepts>
#include <cstddef>
#include <optional>
#include <utility>

#include "estimators/mcmc/chain_step.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

// An unnormalised target density pi(x) >= 0, LINEAR (not log): every target in this project is
// bounded and evaluated in double, and the acceptance ratio is formed as a ratio of products.
template <class T>
concept Target = requires(const T& t, const typename T::State& x) {
  typename T::State;
  { t.density(x) } -> std::convertible_to<double>;
};

// A proposal: y ~ T(x -> .) from uniforms (empty optional when the proposal fails; the missing
// mass then means "stay at x"), and the density T(x -> y) of the proposal in the reference measure
// of the state space, Jacobians of any change of variables included.
template <class P>
concept Proposal = requires(const P& p, const typename P::State& x, const typename P::State& y, Uniforms& u) {
  typename P::State;
  { p.propose(x, u) } -> std::same_as<std::optional<typename P::State>>;
  { p.density(x, y) } -> std::convertible_to<double>;
};

// A finite mixture of proposals T_k chosen with state-dependent probabilities c_k(x), sum_k c_k(x)
// = 1 (Otsu et al., Sec. 3.2, "Combining Multiple Mutation Strategies"; their s(j | x)). The
// acceptance of a move made with component k contains c_k(y) / c_k(x).
template <class M>
concept ProposalMixture = requires(const M& m, const typename M::State& x, const typename M::State& y,
                                   Uniforms& u, int k) {
  typename M::State;
  { m.components() } -> std::convertible_to<int>;
  { m.selection(k, x) } -> std::convertible_to<double>;  // c_k(x), a probability
  { m.propose(k, x, u) } -> std::same_as<std::optional<typename M::State>>;
  { m.density(k, x, y) } -> std::convertible_to<double>;  // T_k(x -> y)
};

// A dimension-matching map for reversible jump (Green 1995, Sec. 3.3): a bijection
// g(x, u) = y between (low-dimensional state x, auxiliary u) and a high-dimensional state y, with
// u ~ q(u). jacobian(x, u) = |det dg/d(x, u)|.
template <class G>
concept DimensionMatchingMap = requires(const G& g, const typename G::Low& x, const typename G::Aux& a,
                                        const typename G::High& y, Uniforms& u) {
  typename G::Low;
  typename G::High;
  typename G::Aux;
  { g.sample_aux(u) } -> std::same_as<typename G::Aux>;
  { g.aux_density(a) } -> std::convertible_to<double>;  // q(u), Lebesgue on the auxiliary space
  { g.up(x, a) } -> std::same_as<typename G::High>;      // y = g(x, u)
  { g.down(y) } -> std::same_as<std::pair<typename G::Low, typename G::Aux>>;  // g^{-1}(y)
  { g.jacobian(x, a) } -> std::convertible_to<double>;  // |det dg/d(x, u)|
};

// A kernel seen through its moves, the form all detailed-balance checkers use. A Move records
// everything the proposal drew (component, destination, auxiliary tries): move_density(x, m) is
// the joint density of proposing m from x and acceptance(x, m) the probability of accepting it;
// reverse(x, m) is the move that takes destination(m) back to x; move_terms(x, m) are the four
// numbers of its Hastings ratio (chain_step.h), from which acceptance(x, m) = decide(move_terms).
// Detailed balance (on the extended space for multiple-try kernels) is
//   pi(x) move_density(x, m) acceptance(x, m) = pi(y) move_density(y, m') acceptance(y, m').
template <class K>
concept MoveKernel = requires(const K& k, const typename K::State& x, const typename K::Move& m, Uniforms& u) {
  typename K::State;
  typename K::Move;
  { k.target_density(x) } -> std::convertible_to<double>;
  { k.sample_move(x, u) } -> std::same_as<std::optional<typename K::Move>>;
  { k.destination(m) } -> std::convertible_to<typename K::State>;
  { k.reverse(x, m) } -> std::same_as<typename K::Move>;
  { k.move_density(x, m) } -> std::convertible_to<double>;
  { k.move_terms(x, m) } -> std::convertible_to<MoveTerms>;
  { k.acceptance(x, m) } -> std::convertible_to<double>;
};

}  // namespace tb::mcmc

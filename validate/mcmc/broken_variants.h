// Deliberately broken kernels and moves: the negative controls every MCMC checker must reject
// (docs/validation.md, "every check has a negative control"). Each is the correct code with one factor
// removed or misstated, built from the same estimators/mcmc/ templates.
#pragma once

#include <optional>
#include <utility>

#include "analytic/mcmc/continuous_proposals.h"
#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/concepts.h"
#include "estimators/mcmc/prefix_multiple_try.h"

namespace tb::mcmc {

// Broken rule: the acceptance ratio without T(y -> x) / T(x -> y) (and without c_k(y) / c_k(x)):
// plain Metropolis, min(1, pi(y) / pi(x)), applied to an asymmetric proposal.
struct MetropolisRatioOnly {
  double operator()(double pi_x, double, double pi_y, double) const { return acceptance_from(pi_y, pi_x); }
};

// Broken map: a reversible-jump move that forgets the Jacobian determinant (states |J| = 1).
template <DimensionMatchingMap G>
class WithoutJacobian {
 public:
  using Low = typename G::Low;
  using High = typename G::High;
  using Aux = typename G::Aux;
  explicit WithoutJacobian(G g) : g_(std::move(g)) {}
  Aux sample_aux(Uniforms& u) const { return g_.sample_aux(u); }
  double aux_density(Aux a) const { return g_.aux_density(a); }
  High up(const Low& x, Aux a) const { return g_.up(x, a); }
  std::pair<Low, Aux> down(const High& y) const { return g_.down(y); }
  double jacobian(const Low&, Aux) const { return 1.0; }

 private:
  G g_;
};

// Broken proposal: samples N(mu, sigma^2), states the density of N(mu, (1.05 sigma)^2).
template <size_t N>
auto misstated_independent_gaussian(Point<N> mu, double sigma, double stated_factor = 1.05) {
  return StatedDensity(IndependentGaussian<N>(mu, sigma), IndependentGaussian<N>(mu, stated_factor * sigma));
}

// Broken multiple-try large step: the prefix move of prefix_multiple_try.h accepted without the
// reverse candidates, min{1, S(U_Y) / pi(x)} (the source's own weight in place of the sum over
// the candidates of U_X = (u, U_X^+)). Proposal and stated density are the real ones.
template <PrefixFamily F>
class WithoutReverseCandidates {
 public:
  using State = typename PrefixMultipleTry<F>::State;
  using Move = typename PrefixMultipleTry<F>::Move;
  explicit WithoutReverseCandidates(PrefixMultipleTry<F> k) : k_(std::move(k)) {}
  const F& target() const { return k_.target(); }
  double target_density(const State& x) const { return k_.target_density(x); }
  std::optional<Move> sample_move(const State& x, Uniforms& u) const { return k_.sample_move(x, u); }
  State destination(const Move& m) const { return k_.destination(m); }
  Move reverse(const State& x, const Move& m) const { return k_.reverse(x, m); }
  double move_density(const State& x, const Move& m) const { return k_.move_density(x, m); }
  MoveTerms move_terms(const State& x, const Move& m) const {
    MoveTerms t = k_.move_terms(x, m);
    t.forward = k_.target_density(x);
    return t;
  }
  double acceptance(const State& x, const Move& m) const { return decide(move_terms(x, m)).acceptance; }

 private:
  PrefixMultipleTry<F> k_;
};

}  // namespace tb::mcmc

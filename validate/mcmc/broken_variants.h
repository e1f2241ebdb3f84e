// Deliberately broken kernels and moves: the negative controls every MCMC checker must reject
// (docs/validation.md, "every check has a negative control"). Each is the correct code with one factor
// removed or misstated, built from the same estimators/mcmc/ templates.
#pragma once

#include <utility>

#include "analytic/mcmc/continuous_proposals.h"
#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/concepts.h"

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

}  // namespace tb::mcmc

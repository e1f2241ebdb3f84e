// A birth/death reversible-jump move (Green 1995, "Reversible jump Markov chain Monte Carlo
// computation and Bayesian model determination", Biometrika 82(4), Sec. 3.3) built from a
// dimension-matching map g(x, u) = y (concepts.h). The state is std::variant<Low, High>: from a low
// state the move is a birth y = g(x, u), u ~ q; from a high state a death x = first(g^{-1}(y)).
//
// Density convention (what density(x, y) means). Both directions are densities of the same
// symmetric measure on pairs, parametrised by the high-dimensional point y (Lebesgue dy):
//   birth  T(x -> y) = q(u) / |det dg/d(x, u)|     (dx du = dy / |J|)
//   death  T(y -> x) = 1                           (x is a deterministic function of y)
// so pi(x) T(x->y) a(x->y) = pi(y) T(y->x) a(y->x) is Green's detailed balance and the MH ratio
// gives his acceptance min(1, pi(y) |J| / (pi(x) q(u))) (Green 1995, Eq. 8, with the move
// probabilities j(x), j(y) supplied by the enclosing mixture as c_k(x), c_k(y)).
#pragma once

#include <optional>
#include <utility>
#include <variant>

#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <DimensionMatchingMap G>
class BirthDeath {
 public:
  using Low = typename G::Low;
  using High = typename G::High;
  using State = std::variant<Low, High>;

  explicit BirthDeath(G map) : g_(std::move(map)) {}
  const G& map() const { return g_; }

  std::optional<State> propose(const State& x, Uniforms& u) const {
    // Built in place: copying a variant holding the smaller alternative trips GCC 12's
    // -Wmaybe-uninitialized on the unused bytes of the larger one.
    std::optional<State> y;
    if (const Low* lo = std::get_if<Low>(&x))
      y.emplace(std::in_place_type<High>, g_.up(*lo, g_.sample_aux(u)));
    else
      y.emplace(std::in_place_type<Low>, g_.down(std::get<High>(x)).first);
    return y;
  }

  // Assumes y is the image of x under the move (as for every pair the move proposes).
  double density(const State& x, const State& y) const {
    if (std::holds_alternative<Low>(x) && std::holds_alternative<High>(y)) {
      const auto [xl, a] = g_.down(std::get<High>(y));
      const double j = g_.jacobian(xl, a);
      return j > 0.0 ? g_.aux_density(a) / j : 0.0;
    }
    if (std::holds_alternative<High>(x) && std::holds_alternative<Low>(y)) return 1.0;
    return 0.0;  // the move never keeps the dimension
  }

 private:
  G g_;
};

}  // namespace tb::mcmc

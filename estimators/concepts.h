// The small concepts every estimator in this folder is written against (ARCHITECTURE.md, "The one
// idea"): an integrand f(x), a classical technique (sample x from uniforms, evaluate p(x)) and a
// marginal technique (sample an auxiliary t, then x | t, evaluate the conditional p(x | t)).
// analytic/ implements them for 1D/2D problems, lib/ for light paths. A Proposal concept for MCMC
// kernels lives in its own header (estimators/proposal_concepts.h, written separately).
#pragma once

#include <concepts>
#include <optional>

#include "lib/core/uniforms.h"

namespace tb {

// f(x): a real-valued function on the sample space of the techniques it is integrated with.
template <class F, class X>
concept Integrand = requires(const F& f, const X& x) {
  { f(x) } -> std::convertible_to<double>;
};

// A classical technique: sample() draws x from uniforms (empty optional when it fails, which makes
// the density a sub-probability one); pdf(x) is the density of x in the same measure as f's domain.
template <class T>
concept Technique = requires(const T& t, const typename T::Sample& x, Uniforms& u) {
  typename T::Sample;
  { t.sample(u) } -> std::same_as<std::optional<typename T::Sample>>;
  { t.pdf(x) } -> std::convertible_to<double>;
};

// A marginal technique (West et al. 2022, Eq. 2): p(x) = ∫ p(x | t) p(t) dt is intractable, but
// t ~ p(t) and x ~ p(x | t) can be sampled and p(x | t) evaluated. Aux identifies a conditional
// technique in the technique space T_i.
template <class T>
concept MarginalTechnique = requires(const T& m, const typename T::Aux& a, const typename T::Sample& x, Uniforms& u) {
  typename T::Aux;
  typename T::Sample;
  { m.sample_aux(u) } -> std::same_as<std::optional<typename T::Aux>>;
  { m.sample(a, u) } -> std::same_as<std::optional<typename T::Sample>>;
  { m.pdf(x, a) } -> std::convertible_to<double>;
};

}  // namespace tb

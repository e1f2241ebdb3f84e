// What the MCMC checkers need from a target beyond pi(x) (estimators/mcmc/concepts.h): exact draws
// from pi, and a partition of the state space into bins with exactly known probabilities (for the
// chi-square and flux tests), and a scalar summary of a state (rank test, diagnostics).
#pragma once

#include <concepts>

#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <class T>
concept ExactTarget = Target<T> && requires(const T& t, const typename T::State& x, Uniforms& u, int i) {
  { t.sample_exact(u) } -> std::convertible_to<typename T::State>;
  { t.bin_count() } -> std::convertible_to<int>;
  { t.bin_of(x) } -> std::convertible_to<int>;      // in [0, bin_count())
  { t.bin_mass(i) } -> std::convertible_to<double>;  // normalised: sums to 1 over the bins
  { t.summary(x) } -> std::convertible_to<double>;
};

// A MoveKernel on a finite space {0..n-1} whose proposal mixture can be enumerated exactly.
template <class K>
concept FiniteMixtureKernel = MoveKernel<K> && std::same_as<typename K::State, int> &&
                              requires(const K& k, int c, int i, int j) {
                                { k.components() } -> std::convertible_to<int>;
                                { k.proposal_density(c, i, j) } -> std::convertible_to<double>;
                                { k.acceptance(c, i, j) } -> std::convertible_to<double>;
                              };

}  // namespace tb::mcmc

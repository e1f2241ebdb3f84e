// A finite toy state space {0, ..., n-1} with arbitrary (hashed, unnormalised) weights pi_i, and
// proposals on it whose transition probabilities are exact: the space on which the transition
// matrix of a kernel is built and checked exactly (docs/validation.md E). Measure: counting measure;
// every "density" here is a probability mass.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "lib/core/discrete.h"
#include "lib/core/hash.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

class FiniteTarget {
 public:
  using State = int;
  explicit FiniteTarget(int n = 64, uint64_t seed = 7) : w_(n) {
    // Weights spread over two orders of magnitude, a few states nearly empty.
    for (int i = 0; i < n; ++i) {
      const double h = static_cast<double>(hash_values(seed, static_cast<uint64_t>(i)) >> 11) * 0x1p-53;
      w_[i] = 0.01 + 3.0 * h * h * h;
    }
    cdf_ = *DiscreteCdf::create(w_);
  }
  int size() const { return static_cast<int>(w_.size()); }
  double density(State i) const { return (i >= 0 && i < size()) ? w_[i] : 0.0; }
  double probability(State i) const { return cdf_.pmf(i); }

  State sample_exact(Uniforms& u) const { return static_cast<int>(cdf_.sample(u.next()).index); }
  int bin_count() const { return size(); }
  int bin_of(State i) const { return i; }
  double bin_mass(int i) const { return cdf_.pmf(i); }
  double summary(State i) const { return i; }

 private:
  std::vector<double> w_;
  DiscreteCdf cdf_;
};

// Steps on a ring with ASYMMETRIC probabilities: +1 w.p. 0.5, -1 w.p. 0.2, +5 w.p. 0.3, so
// T(i -> j) != T(j -> i) and the Hastings ratio matters.
class RingStepProposal {
 public:
  using State = int;
  explicit RingStepProposal(int n) : n_(n) {}
  static constexpr std::array<int, 3> kSteps{+1, -1, +5};
  static constexpr std::array<double, 3> kProb{0.5, 0.2, 0.3};

  std::optional<State> propose(State i, Uniforms& u) const {
    const double v = u.next();
    const int k = v < kProb[0] ? 0 : (v < kProb[0] + kProb[1] ? 1 : 2);
    return wrap(i + kSteps[k]);
  }
  double density(State i, State j) const {
    double p = 0.0;
    for (int k = 0; k < 3; ++k) p += (wrap(i + kSteps[k]) == j) ? kProb[k] : 0.0;
    return p;
  }

 private:
  int wrap(int i) const { return ((i % n_) + n_) % n_; }
  int n_;
};

// An independent proposal j ~ q, with q unrelated to pi (hashed weights).
class FiniteIndependentProposal {
 public:
  using State = int;
  explicit FiniteIndependentProposal(int n, uint64_t seed = 11) {
    std::vector<double> q(n);
    for (int i = 0; i < n; ++i) q[i] = 0.2 + static_cast<double>(hash_values(seed, static_cast<uint64_t>(i)) >> 11) * 0x1p-53;
    cdf_ = *DiscreteCdf::create(q);
  }
  std::optional<State> propose(State, Uniforms& u) const { return static_cast<int>(cdf_.sample(u.next()).index); }
  double density(State, State j) const { return cdf_.pmf(j); }

 private:
  DiscreteCdf cdf_;
};

// State-dependent selection between the ring steps (k = 0) and the independent proposal (k = 1):
// c_1(i) = 0.2 on even states, 0.6 on odd ones.
struct FiniteParitySelection {
  double operator()(int k, int i) const {
    const double c1 = (i % 2 == 0) ? 0.2 : 0.6;
    return k == 1 ? c1 : 1.0 - c1;
  }
};

}  // namespace tb::mcmc

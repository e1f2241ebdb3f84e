// The primary-sample-space chain in the form of the generic MCMC concepts (estimators/mcmc/
// concepts.h), for the detailed-balance checkers: a dense state u in [0,1)^n (n = kStreams *
// uniforms per stream, the layout of pss_state.h), the target I(u) of a sample function at one
// level, and the registered mutations (pss_mutation.h) the renderer runs:
//  - a proposal is made by the renderer's own lazy PssState, started at u (PssState::at), through
//    the mutation's begin(), then read out to n coordinates (those y did not read move as the lazy
//    state moves them when they are next read: by sigma0, or a fresh uniform after a large step);
//  - its density is the mutation's log_density, and its acceptance is formed from pss_move_terms()
//    and mcmc::decide(), the same functions the renderer's chain step uses.
// Lebesgue measure on [0,1)^n is the reference measure of pi and T.
//
// Scale: T of the small step is a product of n densities of height up to 1 / (sigma sqrt(2 pi))
// (about 40 for sigma = 0.01), so n must stay below about 190 for pi T to stay finite in double.
#pragma once

#include <array>
#include <functional>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "lib/mcmc/pss/pss_mutation.h"
#include "lib/mcmc/pss/pss_sample.h"
#include "lib/mcmc/pss/pss_state.h"

namespace tb::pss {

// A chain's scalar target of its splats (empty: target_value, the luminance of their sum), as
// PssSettings::target.
using SplatTarget = std::function<double(const std::vector<Splat>&)>;

// I(u) (or pi(u) of a custom target) and the reads per stream of a sample function on a dense state.
struct DenseEvaluation {
  double value = 0.0;
  std::array<size_t, kStreams> reads{};
};
DenseEvaluation evaluate_dense(const SampleFunction& f, int level, const DenseState& x, const SplatTarget& pi = {});

// I(u) of a sample function at a fixed level (a Target).
class PssTarget {
 public:
  using State = DenseState;
  PssTarget(SampleFunction f, int level, SplatTarget pi = {}) : f_(std::move(f)), level_(level), pi_(std::move(pi)) {}
  double density(const State& x) const { return evaluate_dense(f_, level_, x, pi_).value; }
  DenseEvaluation evaluate(const State& x) const { return evaluate_dense(f_, level_, x, pi_); }
  const SampleFunction& function() const { return f_; }
  const SplatTarget& splat_target() const { return pi_; }
  int level() const { return level_; }

 private:
  SampleFunction f_;
  int level_;
  SplatTarget pi_;
};

// A move between dense states (differences y_i - x_i).
class DenseMove final : public PssMove {
 public:
  DenseMove(const DenseState& x, const DenseState& y) : x_(&x), y_(&y) {}
  double difference(size_t i) const override { return (*y_)[i] - (*x_)[i]; }

 private:
  const DenseState* x_;
  const DenseState* y_;
};

// The Metropolis-Hastings kernel over registered PSS mutations on dense states (a MoveKernel).
class PssKernel {
 public:
  using State = DenseState;
  struct Move {
    int component = 0;
    State y;
  };
  // y_ref: the reference value of a rescaled step (the renderer's bootstrap b); sigma0: the fixed
  // small-step scale, which coordinates outside a rescaled step's D(x) ∩ D(y) move by.
  // pi: a custom target of the splats (empty: I(u), the luminance of their sum).
  PssKernel(SampleFunction f, int level, PssMutationList mutations, double sigma0, double y_ref = 1.0,
            SplatTarget pi = {});

  int components() const { return static_cast<int>(m_.size()); }
  const PssMutation& mutation(int k) const { return *m_[static_cast<size_t>(k)]; }
  const PssTarget& target() const { return target_; }

  // y ~ T_k(x -> .) by the lazy state (see the top of this file).
  std::optional<State> propose(int k, const State& x, Uniforms& u) const;
  // T_k(x -> y), with two departures from the exact density, both on moves the double-precision
  // chain can never make, so that the checkers' products pi T a stay in the normal range:
  //  - a density below 1e-290 (a jump of tens of sigma back) is stated as 0: in the subnormal
  //    range pi T a loses its relative precision;
  //  - a pair (x, y) whose Hastings ratio is below 1e-300 or above 1e300 gets density 0 both ways:
  //    the ratio underflows to an acceptance of 0 in double (in the renderer too), so the move one
  //    way is never accepted while the true flux is ~1e-300 of the reverse move's density.
  double density(int k, const State& x, const State& y) const;
  // The move's PssMove (reads and scales of both ends); *pi_x, *pi_y receive the targets.
  DenseMove move(int k, const State& x, const State& y, double* pi_x = nullptr, double* pi_y = nullptr) const;

  // ---- MoveKernel ----------------------------------------------------------------------------------
  double target_density(const State& x) const { return target_.density(x); }
  std::optional<Move> sample_move(const State& x, Uniforms& u) const;
  const State& destination(const Move& m) const { return m.y; }
  Move reverse(const State& x, const Move& m) const { return Move{m.component, x}; }
  double move_density(const State& x, const Move& m) const;
  mcmc::MoveTerms move_terms(const State& x, const Move& m) const;
  double acceptance(const State& x, const Move& m) const { return mcmc::decide(move_terms(x, m)).acceptance; }

 private:
  PssTarget target_;
  PssMutationList m_;
  double sigma0_, y_ref_;
};

// One mutation as a Proposal (for the proposal chi-square): the kernel's component k.
class PssComponentProposal {
 public:
  using State = DenseState;
  PssComponentProposal(const PssKernel& k, int component) : k_(&k), c_(component) {}
  std::optional<State> propose(const State& x, Uniforms& u) const { return k_->propose(c_, x, u); }
  double density(const State& x, const State& y) const { return k_->density(c_, x, y); }

 private:
  const PssKernel* k_;
  int c_;
};

}  // namespace tb::pss

// Primary-sample-space mutations as registered components. Each mutation is one object that acts
// on the lazily updated PssState the renderer runs (begin: which lazy update the proposal makes) and
// states, for the same move, its density T(x -> y) on Lebesgue measure of [0,1)^n (log_density) and
// the ratio T(y -> x) / T(x -> y) the acceptance uses (log_reverse_over_forward). The renderer's
// chain (pss_driver.cpp) and the dense kernel of the checks (pss_kernel.h) both take the mutations
// from this interface and both form the Hastings terms with pss_move_terms(), so what the pairwise,
// flux and chi-square checks see is the code that renders.
//
// Adding a mutation: a class derived from PssMutation and one line in pss_mutations() (pss_steps.cpp).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "estimators/mcmc/chain_step.h"
#include "lib/mcmc/pss/pss_state.h"

namespace tb::pss {

using DenseState = std::vector<double>;

// A move x -> y in primary sample space as its densities need it: the coordinates each state read
// (D(x), D(y): a prefix of each stream, pss_state.h), the step scales at both ends, and the
// differences y_i - x_i (any representative modulo 1) of the coordinates of D(x) ∩ D(y).
class PssMove {
 public:
  std::array<size_t, kStreams> reads_x{}, reads_y{};
  double sigma_x = 0.0, sigma_y = 0.0;
  virtual double difference(size_t coordinate) const = 0;

 protected:
  ~PssMove() = default;
};

// The lazy state's move while a proposal is evaluated: y_i - x_i of a coordinate of D(x) ∩ D(y)
// (modified in this iteration: its backup is x_i, which x read at the previous iteration with no
// step pending, and its value y_i). The caller sets reads and scales.
class LazyPssMove final : public PssMove {
 public:
  explicit LazyPssMove(const PssState& s) : s_(&s) {}
  double difference(size_t i) const override { return s_->stored(i) - s_->backup(i); }

 private:
  const PssState* s_;
};

// The settings a mutation is built from.
struct PssStepSettings {
  double large_step_probability = 0.3;  // selection weight of the large step; 1 - it for a small step
  double sigma = 0.01;                  // sigma0, the fixed small-step scale
  // Rescaled small step: sigma(x) = clamp(sigma0 (Y_ref / Y(x))^kappa, sigma_min, sigma_max).
  double exponent = 1.0, sigma_min = 1e-4, sigma_max = 0.1;
};

class PssMutation {
 public:
  virtual ~PssMutation() = default;
  virtual std::string name() const = 0;
  virtual double weight() const = 0;  // unnormalised selection weight (state-independent)
  // True for a proposal independent of x (the large step): counted as such in `tb render`'s report.
  virtual bool independent() const { return false; }
  // The step scale at a state of target value pi, y_ref the pass's reference (b); 0: no scale.
  virtual double scale(double pi, double y_ref) const = 0;
  // Starts a proposal from the chain's current state (PssState::start_iteration with the lazy
  // update of this mutation); scale_x = scale(pi(x), y_ref).
  virtual void begin(PssState& s, double scale_x) const = 0;
  // log T(y -> x) / T(x -> y) (0 for a symmetric mutation).
  virtual double log_reverse_over_forward(const PssMove&) const { return 0.0; }
  // True when T(x -> y) = T(y -> x) for all pairs (the ratio is then not evaluated).
  virtual bool symmetric() const { return false; }
  // log T(x -> y) on Lebesgue measure of [0,1)^n, n = x.size() (-inf outside the support).
  virtual double log_density(const DenseState& x, const DenseState& y, const PssMove& m) const = 0;
};

using PssMutationList = std::vector<std::shared_ptr<const PssMutation>>;

// The Hastings terms of a move by a mutation selected with probability c (chain_step.h): the
// factor T(x -> y) common to both sides is dropped, so forward = c and reverse = c T(y->x)/T(x->y).
inline mcmc::MoveTerms pss_move_terms(const PssMutation& m, double c, double pi_x, double pi_y, const PssMove& move) {
  const double ratio = pi_y > 0.0 && !m.symmetric() ? std::exp(m.log_reverse_over_forward(move)) : 1.0;
  return {pi_x, c, pi_y, c * ratio};
}

// c_k of a list: weight_k / sum of weights.
double selection_probability(const PssMutationList& list, int k);
// The component for uniform v (inversion of the running sum of the weights).
int select_mutation(const PssMutationList& list, double v);

// ---- the registry ---------------------------------------------------------------------------------
struct PssMutationInfo {
  std::string name;
  std::string description;
  std::shared_ptr<const PssMutation> (*make)(const PssStepSettings&);
};
// Every registered mutation (pss_steps.cpp holds the table).
const std::vector<PssMutationInfo>& pss_mutations();
const PssMutationInfo* find_pss_mutation(const std::string& name);
// Registers a mutation at run time (outside code and tests); the checks that loop over
// pss_mutations() pick it up. Not thread-safe: register before running anything.
void register_pss_mutation(PssMutationInfo info);
// Removes a mutation registered at run time (tests that register one clean up after themselves).
void unregister_pss_mutation(const std::string& name);
// The list a name list makes, from the registry (throws std::invalid_argument naming an unknown one).
PssMutationList make_pss_mutations(const std::vector<std::string>& names, const PssStepSettings& s);

}  // namespace tb::pss

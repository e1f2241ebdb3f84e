// The primary-sample-space chain in the form of the generic MCMC concepts (estimators/mcmc/
// concepts.h), for the detailed-balance checkers of validate/mcmc/: a dense state u in [0,1)^n
// (n = kStreams * uniforms per stream, the layout of pss_state.h), the target I(u) of a sample
// function at one level, and the two mutations as Proposals with their densities:
//   SmallStep  y_i = x_i + sigma z_i mod 1,  T(x -> y) = prod_i g_sigma(y_i - x_i)  (symmetric);
//   LargeStep  y uniform on [0,1)^n,        T(x -> y) = 1.
// Lebesgue measure on [0,1)^n is the reference measure of pi and T. The lazily updated PssState
// the renderer runs makes the same moves (its coordinates beyond those read are perturbed too,
// lazily); tests/render/mcmc_pss_test.cpp checks the lazy update against these densities.
//
// Scale: T of the small step is a product of n densities of height up to 1 / (sigma sqrt(2 pi))
// (about 40 for sigma = 0.01), so n must stay below about 190 for pi T to stay finite in double.
#pragma once

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "estimators/mcmc/concepts.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/proposal_mixture.h"
#include "lib/mcmc/pss/pss_sample.h"
#include "lib/mcmc/pss/pss_state.h"

namespace tb::pss {

using DenseState = std::vector<double>;

// I(u) of a sample function at a fixed level (a Target).
class PssTarget {
 public:
  using State = DenseState;
  PssTarget(SampleFunction f, int level) : f_(std::move(f)), level_(level) {}
  double density(const State& x) const {
    thread_local std::vector<Splat> sp;
    sp.clear();
    DenseStreams u(x);
    f_.sample(level_, u, &sp);
    const double i = target_value(sp);
    return std::isfinite(i) && i > 0.0 ? i : 0.0;
  }

 private:
  SampleFunction f_;
  int level_;
};

class SmallStep {
 public:
  using State = DenseState;
  explicit SmallStep(double sigma) : sigma_(sigma) {}
  std::optional<State> propose(const State& x, Uniforms& u) const {
    State y(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      const double u1 = 1.0 - u.next(), u2 = u.next();  // Box & Muller 1958
      const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
      y[i] = wrap01(x[i] + sigma_ * z);
    }
    return y;
  }
  double density(const State& x, const State& y) const {
    double p = 1.0;
    for (size_t i = 0; i < x.size(); ++i) p *= wrapped_normal_pdf(y[i] - x[i], sigma_);
    return p;
  }

 private:
  double sigma_;
};

class LargeStep {
 public:
  using State = DenseState;
  std::optional<State> propose(const State& x, Uniforms& u) const {
    State y(x.size());
    for (double& v : y) v = u.next();
    return y;
  }
  double density(const State&, const State& y) const {
    for (double v : y)
      if (!(v >= 0.0 && v < 1.0)) return 0.0;
    return 1.0;
  }
};

// State-independent selection: the large step with probability p_large.
struct LargeStepSelection {
  double p_large = 0.3;
  double operator()(int k, const DenseState&) const { return k == 0 ? 1.0 - p_large : p_large; }
};

using PssMixture = mcmc::Mixture<LargeStepSelection, SmallStep, LargeStep>;

// The kernel the renderer runs, as a MoveKernel: Metropolis-Hastings over the mixture.
inline mcmc::MetropolisHastings<PssTarget, PssMixture> make_pss_kernel(const SampleFunction& f, int level,
                                                                       double sigma, double p_large) {
  return {PssTarget(f, level), PssMixture(LargeStepSelection{p_large}, SmallStep(sigma), LargeStep())};
}

}  // namespace tb::pss

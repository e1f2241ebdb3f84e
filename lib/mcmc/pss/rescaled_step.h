// Isotropic small-step rescaling by the current path's contribution (Szirmay-Kalos & Szecsi 2017,
// "Improved stratification for Metropolis light transport", as Zirr & Dachsbacher 2020 describe it
// in Sec. 8: "an isotropic proposal distribution in primary sample space is scaled to a standard
// deviation that is inversely proportional to the throughput of the current path"):
//   sigma(x) = clamp(sigma0 * (Y_ref / Y(x))^kappa, sigma_min, sigma_max),
// Y(x) the chain's scalar target at x (the luminance of f for PSSMLT), Y_ref the bootstrap
// estimate b of its mean (fixed for a pass, so the kernel is fixed while the chains run), kappa = 1
// ("inversely proportional"; the exponent is a setting). Bright paths take small steps, dim paths
// large ones: the chain leaves bright regions sooner, which spreads mutations more evenly.
//
// With a state-dependent sigma the proposal is not symmetric. Which coordinates take sigma(x):
// those read by both the current state and the proposal, D(x) ∩ D(y); all others the fixed sigma0
// (pss_state.h explains why this is a proper proposal; with lazy primary samples every coordinate
// outside D(x) ∩ D(y) keeps moving by sigma0, whose factors cancel in the ratio):
//   T(x -> y) = prod_{i in D(x) ∩ D(y)} g_{sigma(x)}(y_i - x_i) * prod_{other i} g_{sigma0}(y_i - x_i),
//   a(x -> y) = min(1, pi(y) T(y -> x) / (pi(x) T(x -> y))).
// Perturbing every coordinate by sigma(x) would not do: over the infinitely many coordinates of a
// lazy state the product of g_{sigma(y)} / g_{sigma(x)} has no limit (the two infinite products of
// Gaussians are mutually singular measures when sigma(x) != sigma(y)).
//
// RescaledSmallStep is that proposal on a dense state (pss_kernel.h's DenseState) as a Proposal
// for the checkers; the renderer's lazy PssState (set_rescaled) makes the same move and computes
// the same ratio (PssState::log_small_step_ratio); tests/render/mcmc_pss_test.cpp compares them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

#include "lib/mcmc/pss/pss_kernel.h"

namespace tb::pss {

struct StepRescaling {
  bool enabled = false;
  double exponent = 1.0;     // kappa: sigma inversely proportional to Y (Zirr 2020, Sec. 8)
  double sigma_min = 1e-4;   // keeps the step above the double resolution of wrapped Gaussians
  double sigma_max = 0.1;    // beyond ~0.3 the wrapped Gaussian is nearly uniform: a large step
  // sigma(x) for target value y, reference y_ref, base step sigma0 (y > 0, y_ref > 0).
  double sigma(double sigma0, double y_ref, double y) const {
    if (!(y > 0.0) || !(y_ref > 0.0)) return sigma_max;
    return std::clamp(sigma0 * std::pow(y_ref / y, exponent), sigma_min, sigma_max);
  }
};

// I(u) and the reads per stream of a sample function on a dense state.
struct DenseEvaluation {
  double value = 0.0;
  std::array<size_t, kStreams> reads{};
};
inline DenseEvaluation evaluate_dense(const SampleFunction& f, int level, const DenseState& x) {
  thread_local std::vector<Splat> sp;
  sp.clear();
  DenseStreams u(x);
  f.sample(level, u, &sp);
  const double i = target_value(sp);
  return {std::isfinite(i) && i > 0.0 ? i : 0.0, u.reads()};
}

class RescaledSmallStep {
 public:
  using State = DenseState;
  RescaledSmallStep(SampleFunction f, int level, double sigma0, double y_ref, StepRescaling r)
      : f_(std::move(f)), level_(level), sigma0_(sigma0), y_ref_(y_ref), r_(r) {}

  double sigma_at(double y) const { return r_.sigma(sigma0_, y_ref_, y); }

  // Draws z_i for every coordinate, then evaluates y sequentially: a coordinate y reads gets
  // sigma(x) if x read it too, sigma0 otherwise; coordinates y never reads get sigma0.
  std::optional<State> propose(const State& x, Uniforms& u) const {
    const DenseEvaluation ex = evaluate_dense(f_, level_, x);
    const double sx = sigma_at(ex.value);
    State z(x.size());
    for (double& v : z) {
      const double u1 = 1.0 - u.next(), u2 = u.next();  // Box & Muller 1958
      v = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
    }
    State y(x.size());
    for (size_t i = 0; i < x.size(); ++i) y[i] = wrap01(x[i] + sigma0_ * z[i]);
    // Evaluating y reads its coordinates in order; each read coordinate that x read too takes
    // sigma(x). What y reads next depends only on what it read before, as in the lazy PssState.
    ProposalStreams ps(x, z, ex.reads, sx, &y);
    thread_local std::vector<Splat> sp;
    sp.clear();
    f_.sample(level_, ps, &sp);
    return y;
  }

  // T(x -> y) on Lebesgue measure of [0,1)^n (see the top of this file).
  // Two departures from the exact density, both on moves the double-precision chain can never
  // make, so that the checkers' products pi T a stay in the normal range of doubles:
  //  - a density below 1e-290 (a jump of tens of sigma back) is stated as 0: in the subnormal
  //    range pi T a loses its relative precision;
  //  - a pair (x, y) whose Hastings ratio pi(y) T(y -> x) / (pi(x) T(x -> y)) is below 1e-300 or
  //    above 1e300 gets density 0 both ways: the ratio underflows to an acceptance of 0 in double
  //    (in the renderer too: PssState::log_small_step_ratio is exponentiated), so the move one way
  //    is never accepted while the true flux is ~1e-300 of the reverse move's density.
  double density(const State& x, const State& y) const {
    const double lf = log_density(x, y);
    if (lf < kLogFlush) return 0.0;
    const double px = evaluate_dense(f_, level_, x).value, py = evaluate_dense(f_, level_, y).value;
    if (px > 0.0 && py > 0.0) {
      const double log_ratio = std::log(py) + log_density(y, x) - std::log(px) - lf;
      if (std::abs(log_ratio) > kLogRatioFlush) return 0.0;
    }
    return std::exp(lf);
  }
  // log T(x -> y), summed per coordinate (no underflow of the product).
  double log_density(const State& x, const State& y) const {
    const DenseEvaluation ex = evaluate_dense(f_, level_, x), ey = evaluate_dense(f_, level_, y);
    const double sx = sigma_at(ex.value);
    double lp = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      const size_t j = i / kStreams, s = i % kStreams;
      const bool shared = j < ex.reads[s] && j < ey.reads[s];
      lp += std::log(wrapped_normal_pdf(y[i] - x[i], shared ? sx : sigma0_));
    }
    return lp;
  }

 private:
  static constexpr double kLogFlush = -667.7;       // log(1e-290)
  static constexpr double kLogRatioFlush = 690.7;   // -log(1e-300)

  // Streams that build y while it is read (the layout of pss_state.h).
  class ProposalStreams final : public StreamUniforms {
   public:
    ProposalStreams(const State& x, const State& z, const std::array<size_t, kStreams>& x_reads, double sx, State* y)
        : x_(x), z_(z), x_reads_(x_reads), sx_(sx), y_(y) {}
    double next() override {
      const size_t j = index_[static_cast<size_t>(stream_)]++, s = static_cast<size_t>(stream_);
      const size_t i = j * kStreams + s;
      if (i >= y_->size()) throw std::out_of_range("RescaledSmallStep: coordinate beyond the state's dimension");
      if (j < x_reads_[s]) (*y_)[i] = wrap01(x_[i] + sx_ * z_[i]);
      return (*y_)[i];
    }
    void use_stream(int stream) override { stream_ = stream; }
    void restart() override { index_.fill(0); }

   private:
    const State& x_;
    const State& z_;
    std::array<size_t, kStreams> x_reads_;
    double sx_;
    State* y_;
    int stream_ = 0;
    std::array<size_t, kStreams> index_{};
  };

  SampleFunction f_;
  int level_;
  double sigma0_, y_ref_;
  StepRescaling r_;
};

}  // namespace tb::pss

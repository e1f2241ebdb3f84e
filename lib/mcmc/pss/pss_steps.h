// The registered primary-sample-space mutations (Kelemen et al. 2002, Sec. 3 and 4; the rescaled
// small step of Szirmay-Kalos & Szecsi 2017 as Zirr & Dachsbacher 2020, Sec. 8 describe it):
//   "large step"          y uniform on [0,1)^n; T(x -> y) = 1 (symmetric);
//   "small step"          y_i = x_i + sigma0 z_i mod 1; T = prod_i g_sigma0(y_i - x_i) (symmetric);
//   "rescaled small step" sigma(x) = clamp(sigma0 (Y_ref / Y(x))^kappa, sigma_min, sigma_max) on
//                         D(x) ∩ D(y), sigma0 elsewhere (pss_state.h says why this is a proper proposal):
//       T(x -> y) = prod_{i in D(x) ∩ D(y)} g_{sigma(x)}(y_i - x_i) prod_{other i} g_{sigma0}(y_i - x_i),
//       T(y -> x) / T(x -> y) = prod_{i in D(x) ∩ D(y)} g_{sigma(y)}(d_i) / g_{sigma(x)}(d_i)
//       (g even, d_i = y_i - x_i; the sigma0 factors cancel pairwise).
// g_sigma is the wrapped normal density of pss_state.h. The lazy PssState makes each move
// (pss_state.h, "Lazy updates"); these classes say which and state its densities.
#pragma once

#include "lib/mcmc/pss/pss_mutation.h"

namespace tb::pss {

class LargeStep final : public PssMutation {
 public:
  explicit LargeStep(const PssStepSettings& s) : p_(s.large_step_probability) {}
  std::string name() const override { return "large step"; }
  double weight() const override { return p_; }
  bool independent() const override { return true; }
  bool symmetric() const override { return true; }
  double scale(double, double) const override { return 0.0; }
  void begin(PssState& s, double) const override { s.start_iteration(true); }
  double log_density(const DenseState& x, const DenseState& y, const PssMove& m) const override;

 private:
  double p_;
};

class SmallStep final : public PssMutation {
 public:
  explicit SmallStep(const PssStepSettings& s) : w_(1.0 - s.large_step_probability), sigma_(s.sigma) {}
  std::string name() const override { return "small step"; }
  double weight() const override { return w_; }
  bool symmetric() const override { return true; }
  double scale(double, double) const override { return sigma_; }
  void begin(PssState& s, double) const override {
    s.set_rescaled(false);
    s.start_iteration(false);
  }
  double log_density(const DenseState& x, const DenseState& y, const PssMove& m) const override;

 private:
  double w_, sigma_;
};

class RescaledSmallStep final : public PssMutation {
 public:
  explicit RescaledSmallStep(const PssStepSettings& s) : w_(1.0 - s.large_step_probability), s_(s) {}
  std::string name() const override { return "rescaled small step"; }
  double weight() const override { return w_; }
  // sigma(x) for target value pi and reference y_ref (sigma_max where either is not positive).
  double scale(double pi, double y_ref) const override;
  void begin(PssState& s, double scale_x) const override {
    s.set_rescaled(true);
    s.start_iteration(false, scale_x);
  }
  double log_reverse_over_forward(const PssMove& m) const override;
  double log_density(const DenseState& x, const DenseState& y, const PssMove& m) const override;

 private:
  double w_;
  PssStepSettings s_;
};

}  // namespace tb::pss

// A banana (Rosenbrock-like) density on R^2 (Haario, Saksman & Tamminen 1999, "Adaptive proposal
// distribution for random walk Metropolis", Sec. 4, the "twisted Gaussian"):
//   pi(x1, x2) = N(x1; 0, a^2) N(x2; b (x1^2 - a^2), s^2),
// so the marginal of x1 is N(0, a^2) exactly and z = (x2 - b (x1^2 - a^2)) / s is N(0, 1) and
// independent of x1. Bins are a product grid in (x1, z), whose masses are products of normal CDF
// differences. Measure: Lebesgue on R^2 (the map (x1, x2) -> (x1, z) has constant Jacobian 1/s).
#pragma once

#include "analytic/mcmc/grid_bins.h"
#include "analytic/mcmc/normal.h"

namespace tb::mcmc {

class BananaTarget {
 public:
  using State = Point<2>;
  BananaTarget(double a = 1.5, double b = 0.6, double s = 0.5)
      : a_(a), b_(b), s_(s), bins_({-3.0 * a, -3.0}, {3.0 * a, 3.0}, 11) {}

  double density(const State& x) const { return normal_pdf(x[0], 0.0, a_) * normal_pdf(x[1], ridge(x[0]), s_); }
  double ridge(double x1) const { return b_ * (x1 * x1 - a_ * a_); }
  // Marginal of x1: N(0, a^2).
  double marginal_x1_pdf(double x1) const { return normal_pdf(x1, 0.0, a_); }

  State sample_exact(Uniforms& u) const {
    const double x1 = a_ * standard_normal(u);
    return {x1, ridge(x1) + s_ * standard_normal(u)};
  }
  Point<2> to_bin_space(const State& x) const { return {x[0], (x[1] - ridge(x[0])) / s_}; }
  int bin_count() const { return bins_.count(); }
  int bin_of(const State& x) const { return bins_.index(to_bin_space(x)); }
  double bin_mass(int i) const {
    const auto c = bins_.cell(i);
    return normal_mass(bins_.lower(0, c[0]), bins_.upper(0, c[0]), 0.0, a_) *
           normal_mass(bins_.lower(1, c[1]), bins_.upper(1, c[1]), 0.0, 1.0);
  }
  double summary(const State& x) const { return x[1]; }

 private:
  double a_, b_, s_;
  GridBins<2> bins_;
};

}  // namespace tb::mcmc

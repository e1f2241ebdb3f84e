// A trans-dimensional target for reversible jump: model k = 1 on R, model k = 2 on R^2, with known
// model probabilities p1, p2 = 1 - p1:
//   pi(1, x)  = p1 N(x; m1, s1^2),   pi(2, y) = p2 N(y1; m2[0], s2[0]^2) N(y2; m2[1], s2[1]^2).
// Measure: the disjoint union of Lebesgue measures on R and R^2. State: std::variant<Point<1>,
// Point<2>>. Bins: a grid on x for model 1 and a product grid on (y1, y2) for model 2, with exact
// masses (p_k times products of normal CDF differences), so one chi-square tests both the model
// probabilities and the within-model distributions.
//
// The dimension-matching map (CubicSplitMap) between them has a non-constant Jacobian:
//   g(x, u) = (x + s u, x - s u - c u^3),  |det dg/d(x, u)| = 2 s + 3 c u^2,
// inverted by solving the depressed cubic c u^3 + 2 s u = y1 - y2 (one real root since s, c > 0).
#pragma once

#include <cmath>
#include <optional>
#include <utility>
#include <variant>

#include "analytic/mcmc/grid_bins.h"
#include "analytic/mcmc/normal.h"

namespace tb::mcmc {

using TransDimState = std::variant<Point<1>, Point<2>>;

inline int model_of(const TransDimState& x) { return std::holds_alternative<Point<1>>(x) ? 1 : 2; }

class TransDimensionalTarget {
 public:
  using State = TransDimState;
  explicit TransDimensionalTarget(double p1 = 0.35) : p1_(p1) {}

  double model_probability(int k) const { return k == 1 ? p1_ : 1.0 - p1_; }
  double density(const State& x) const {
    if (const auto* a = std::get_if<Point<1>>(&x)) return 2.5 * p1_ * normal_pdf((*a)[0], kM1, kS1);
    const auto& b = std::get<Point<2>>(x);
    return 2.5 * (1.0 - p1_) * normal_pdf(b[0], kM2[0], kS2[0]) * normal_pdf(b[1], kM2[1], kS2[1]);
  }
  State sample_exact(Uniforms& u) const {
    if (u.next() < p1_) return Point<1>{kM1 + kS1 * standard_normal(u)};
    const double y1 = kM2[0] + kS2[0] * standard_normal(u);
    return Point<2>{y1, kM2[1] + kS2[1] * standard_normal(u)};
  }

  int bin_count() const { return bins1_.count() + bins2_.count(); }
  int bin_of(const State& x) const {
    if (const auto* a = std::get_if<Point<1>>(&x)) return bins1_.index(*a);
    return bins1_.count() + bins2_.index(std::get<Point<2>>(x));
  }
  double bin_mass(int i) const {
    if (i < bins1_.count()) {
      const auto c = bins1_.cell(i);
      return p1_ * normal_mass(bins1_.lower(0, c[0]), bins1_.upper(0, c[0]), kM1, kS1);
    }
    const auto c = bins2_.cell(i - bins1_.count());
    return (1.0 - p1_) * normal_mass(bins2_.lower(0, c[0]), bins2_.upper(0, c[0]), kM2[0], kS2[0]) *
           normal_mass(bins2_.lower(1, c[1]), bins2_.upper(1, c[1]), kM2[1], kS2[1]);
  }
  // Model 1 maps to its coordinate, model 2 to its first coordinate shifted by 100.
  double summary(const State& x) const {
    if (const auto* a = std::get_if<Point<1>>(&x)) return (*a)[0];
    return 100.0 + std::get<Point<2>>(x)[0];
  }

  static constexpr double kM1 = 0.5, kS1 = 1.0;
  static constexpr Point<2> kM2{1.0, -0.5}, kS2{0.8, 1.3};

 private:
  double p1_;
  GridBins<1> bins1_{{-3.0}, {4.0}, 13};
  GridBins<2> bins2_{{-1.5, -3.5}, {3.5, 2.5}, 6};
};

class CubicSplitMap {
 public:
  using Low = Point<1>;
  using High = Point<2>;
  using Aux = double;
  CubicSplitMap(double s = 1.0, double c = 0.5) : s_(s), c_(c) {}

  Aux sample_aux(Uniforms& u) const { return standard_normal(u); }
  double aux_density(Aux a) const { return normal_pdf(a, 0.0, 1.0); }  // q(u) = N(0, 1)
  High up(const Low& x, Aux a) const { return {x[0] + s_ * a, x[0] - s_ * a - c_ * a * a * a}; }
  std::pair<Low, Aux> down(const High& y) const {
    // c u^3 + 2 s u - d = 0 with d = y1 - y2: Cardano (p = 2s/c > 0, one real root), then one
    // Newton step to clean the rounding of the cube roots.
    const double d = y[0] - y[1];
    const double p = 2.0 * s_ / c_, q = -d / c_;
    const double disc = std::sqrt(q * q / 4.0 + p * p * p / 27.0);
    double u = std::cbrt(-q / 2.0 + disc) + std::cbrt(-q / 2.0 - disc);
    for (int it = 0; it < 2; ++it) u -= (c_ * u * u * u + 2.0 * s_ * u - d) / (3.0 * c_ * u * u + 2.0 * s_);
    return {Low{y[0] - s_ * u}, u};
  }
  double jacobian(const Low&, Aux a) const { return 2.0 * s_ + 3.0 * c_ * a * a; }

 private:
  double s_, c_;
};

// A random walk inside the current model (never changes the dimension).
class ModelwiseRandomWalk {
 public:
  using State = TransDimState;
  explicit ModelwiseRandomWalk(double sigma) : sigma_(sigma) {}
  std::optional<State> propose(const State& x, Uniforms& u) const {
    if (const auto* a = std::get_if<Point<1>>(&x)) return State{Point<1>{(*a)[0] + sigma_ * standard_normal(u)}};
    const auto& b = std::get<Point<2>>(x);
    const double y1 = b[0] + sigma_ * standard_normal(u);
    return State{Point<2>{y1, b[1] + sigma_ * standard_normal(u)}};
  }
  double density(const State& x, const State& y) const {
    if (x.index() != y.index()) return 0.0;
    if (const auto* a = std::get_if<Point<1>>(&x)) return normal_pdf(std::get<Point<1>>(y)[0], (*a)[0], sigma_);
    const auto& b = std::get<Point<2>>(x);
    const auto& c = std::get<Point<2>>(y);
    return normal_pdf(c[0], b[0], sigma_) * normal_pdf(c[1], b[1], sigma_);
  }

 private:
  double sigma_;
};

// Selection for (k = 0) the birth/death jump and (k = 1) the within-model walk: jumps are tried
// with probability 0.3 from model 1 and 0.6 from model 2, so c_0(y) / c_0(x) enters the ratio.
struct ModelSelection {
  double operator()(int k, const TransDimState& x) const {
    const double c0 = model_of(x) == 1 ? 0.3 : 0.6;
    return k == 0 ? c0 : 1.0 - c0;
  }
};

}  // namespace tb::mcmc

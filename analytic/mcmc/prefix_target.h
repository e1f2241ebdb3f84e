// A prefix family with closed-form masses for the multiple-try large step of
// estimators/mcmc/prefix_multiple_try.h (Zirr & Dachsbacher 2020, Sec. 7.2, App. D): models
// j = 0, 1, 2 on [0,1)^{j+1} (Lebesgue measure on each, their disjoint union), target
//   pi(j, u) = s p_j prod_{i <= j} (a_i + 1) u_i^{a_i},   a = (1, 2, 0.5),  p = (0.2, 0.5, 0.3),
// unnormalised by s = 2.5: the mass of model j is p_j, within a model the coordinates are
// independent with CDF u^{a_i + 1}. The candidates of a draw U in [0,1)^3 are its prefixes of
// lengths 1, 2 and 3, with correlated weights (they share U_0), as the prefixes of one traced path.
// Bins: the model, 8 cells of u_0 and (models 1, 2) 4 cells of u_1, exact masses.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "estimators/mcmc/prefix_multiple_try.h"
#include "lib/core/uniforms.h"

namespace tb::mcmc {

class PrefixTarget {
 public:
  using State = ModelState;
  static constexpr int kModels = 3;
  static constexpr std::array<double, 3> kExponent{1.0, 2.0, 0.5};
  static constexpr std::array<double, 3> kMass{0.2, 0.5, 0.3};
  static constexpr double kScale = 2.5;
  static constexpr int kCells0 = 8, kCells1 = 4;

  int models() const { return kModels; }
  size_t dimension(int j) const { return static_cast<size_t>(j + 1); }
  double density(const State& x) const {
    if (x.model < 0 || x.model >= kModels || x.u.size() != dimension(x.model)) return 0.0;
    return kScale * kMass[static_cast<size_t>(x.model)] * product(x.u, dimension(x.model));
  }
  // W_j(U) = pi(j, U[0, j]) for every j, in one pass over the coordinates.
  void weights(const std::vector<double>& U, std::vector<double>* w) const {
    double prod = 1.0;
    for (int j = 0; j < kModels; ++j) {
      prod *= factor(static_cast<size_t>(j), U[static_cast<size_t>(j)]);
      (*w)[static_cast<size_t>(j)] = kScale * kMass[static_cast<size_t>(j)] * prod;
    }
  }

  State sample_exact(Uniforms& u) const {
    const double v = u.next();
    const int j = v < kMass[0] ? 0 : v < kMass[0] + kMass[1] ? 1 : 2;
    State x{j, std::vector<double>(dimension(j))};
    for (size_t i = 0; i < x.u.size(); ++i) x.u[i] = std::pow(u.next(), 1.0 / (kExponent[i] + 1.0));
    return x;
  }
  int bin_count() const { return kCells0 + 2 * kCells0 * kCells1; }
  int bin_of(const State& x) const {
    const int c0 = cell(x.u[0], kCells0);
    if (x.model == 0) return c0;
    return kCells0 + (x.model - 1) * kCells0 * kCells1 + c0 * kCells1 + cell(x.u[1], kCells1);
  }
  double bin_mass(int b) const {
    if (b < kCells0) return kMass[0] * cdf_mass(0, b, kCells0);
    const int r = b - kCells0, model = 1 + r / (kCells0 * kCells1), c = r % (kCells0 * kCells1);
    return kMass[static_cast<size_t>(model)] * cdf_mass(0, c / kCells1, kCells0) * cdf_mass(1, c % kCells1, kCells1);
  }
  double summary(const State& x) const { return 10.0 * x.model + x.u[0]; }

 private:
  static double factor(size_t i, double u) { return (kExponent[i] + 1.0) * std::pow(u, kExponent[i]); }
  static double product(const std::vector<double>& u, size_t n) {
    double p = 1.0;
    for (size_t i = 0; i < n; ++i) p *= factor(i, u[i]);
    return p;
  }
  static int cell(double u, int n) { return std::min(n - 1, std::max(0, static_cast<int>(u * n))); }
  static double cdf_mass(size_t i, int c, int n) {
    const double a = static_cast<double>(c) / n, b = static_cast<double>(c + 1) / n;
    return std::pow(b, kExponent[i] + 1.0) - std::pow(a, kExponent[i] + 1.0);
  }
};

}  // namespace tb::mcmc

// Gaussian mixtures in N = 1 or 2 dimensions with diagonal covariances and well separated modes:
// the classic hard case for local MCMC moves. Known in closed form: the normalisation, the
// marginals, exact draws, and the mass of every cell of a product grid (products of normal CDF
// differences). The density is returned times an arbitrary constant (`scale`) so that nothing
// relies on normalisation. Measure: Lebesgue on R^N.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "analytic/mcmc/grid_bins.h"
#include "analytic/mcmc/normal.h"

namespace tb::mcmc {

template <size_t N>
class GaussianMixtureTarget {
 public:
  using State = Point<N>;
  struct Component {
    double weight = 1.0;  // normalised over components by the constructor
    Point<N> mean{};
    Point<N> sigma{};
  };

  GaussianMixtureTarget(std::vector<Component> comps, GridBins<N> bins, double scale = 3.7)
      : comps_(std::move(comps)), bins_(std::move(bins)), scale_(scale) {
    double s = 0.0;
    for (const auto& c : comps_) s += c.weight;
    for (auto& c : comps_) c.weight /= s;
  }

  double density(const State& x) const { return scale_ * normalized_density(x); }
  double normalized_density(const State& x) const {
    double p = 0.0;
    for (const auto& c : comps_) {
      double q = c.weight;
      for (size_t d = 0; d < N; ++d) q *= normal_pdf(x[d], c.mean[d], c.sigma[d]);
      p += q;
    }
    return p;
  }
  double normalization() const { return scale_; }

  State sample_exact(Uniforms& u) const {
    const double uc = u.next();
    size_t k = 0;
    double acc = comps_[0].weight;
    while (k + 1 < comps_.size() && uc >= acc) acc += comps_[++k].weight;
    State x{};
    for (size_t d = 0; d < N; ++d) x[d] = comps_[k].mean[d] + comps_[k].sigma[d] * standard_normal(u);
    return x;
  }

  int bin_count() const { return bins_.count(); }
  int bin_of(const State& x) const { return bins_.index(x); }
  double bin_mass(int i) const {
    const auto c = bins_.cell(i);
    double m = 0.0;
    for (const auto& comp : comps_) {
      double q = comp.weight;
      for (size_t d = 0; d < N; ++d)
        q *= normal_mass(bins_.lower(d, c[d]), bins_.upper(d, c[d]), comp.mean[d], comp.sigma[d]);
      m += q;
    }
    return m;
  }
  // Scalar summary for rank tests and diagnostics: the first coordinate.
  double summary(const State& x) const { return x[0]; }
  const std::vector<Component>& components() const { return comps_; }

 private:
  std::vector<Component> comps_;
  GridBins<N> bins_;
  double scale_;
};

// The 1D bimodal target used by the checks: 0.3 N(-3, 0.7^2) + 0.7 N(2.5, 1).
inline GaussianMixtureTarget<1> bimodal_1d() {
  return GaussianMixtureTarget<1>({{0.3, {-3.0}, {0.7}}, {0.7, {2.5}, {1.0}}}, GridBins<1>({-6.0}, {6.0}, 23));
}
// The 2D target: three modes at distinct distances with unequal widths.
inline GaussianMixtureTarget<2> trimodal_2d() {
  return GaussianMixtureTarget<2>({{0.5, {-2.0, -1.5}, {0.8, 0.6}},
                                   {0.3, {2.5, 0.5}, {0.6, 1.0}},
                                   {0.2, {-0.5, 3.0}, {1.0, 0.5}}},
                                  GridBins<2>({-4.5, -3.5}, {4.5, 4.5}, 9));
}

}  // namespace tb::mcmc

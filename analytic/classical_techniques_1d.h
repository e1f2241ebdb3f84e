// Classical 1D techniques (readily evaluable p(x), Lebesgue measure on the real line, support in an
// interval): uniform, truncated normal, piecewise constant, and mixtures of these. Each satisfies
// tb::Technique with Sample = double; Classical1D holds any of them, so that one estimator call can
// combine different families. breakpoints() lists where the density is discontinuous (for quadrature).
#pragma once

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "analytic/truncated_normal_1d.h"
#include "lib/core/uniforms.h"

namespace tb {

// p(x) = 1 / (hi - lo) on [lo, hi].
struct UniformTechnique1D {
  using Sample = double;
  double lo = 0.0, hi = 1.0;
  std::optional<double> sample(Uniforms& u) const { return lo + u.next() * (hi - lo); }
  double pdf(double x) const { return (x >= lo && x <= hi) ? 1.0 / (hi - lo) : 0.0; }
  std::vector<double> breakpoints() const { return {lo, hi}; }
};

// N(mu, sigma²) truncated to [lo, hi].
struct TruncatedNormalTechnique1D {
  using Sample = double;
  TruncatedNormal1D dist;
  TruncatedNormalTechnique1D(double mu, double sigma, double lo = 0.0, double hi = 1.0) : dist(mu, sigma, lo, hi) {}
  std::optional<double> sample(Uniforms& u) const { return dist.sample(u.next()); }
  double pdf(double x) const { return dist.pdf(x); }
  std::vector<double> breakpoints() const { return {dist.lo(), dist.hi()}; }
};

// Piecewise-constant density on edges[0] < ... < edges[k] with cell masses proportional to weights.
class PiecewiseConstantTechnique1D {
 public:
  using Sample = double;
  PiecewiseConstantTechnique1D(std::vector<double> edges, std::vector<double> weights) : edges_(std::move(edges)) {
    if (edges_.size() != weights.size() + 1 || weights.empty())
      throw std::invalid_argument("piecewise constant: need one weight per cell");
    double total = 0.0;
    for (double w : weights) total += w;
    cdf_.push_back(0.0);
    for (size_t i = 0; i < weights.size(); ++i) {
      density_.push_back(weights[i] / total / (edges_[i + 1] - edges_[i]));
      cdf_.push_back(cdf_.back() + weights[i] / total);
    }
    cdf_.back() = 1.0;
  }
  std::optional<double> sample(Uniforms& u) const {
    const double r = u.next();
    const size_t i = std::min<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), r) - cdf_.begin() - 1, density_.size() - 1);
    const double cell = cdf_[i + 1] - cdf_[i];
    if (cell <= 0.0) return std::nullopt;  // only reachable through round-off
    const double s = std::clamp((r - cdf_[i]) / cell, 0.0, 1.0);
    return edges_[i] + s * (edges_[i + 1] - edges_[i]);
  }
  double pdf(double x) const {
    if (x < edges_.front() || x > edges_.back()) return 0.0;
    const size_t i = std::min<size_t>(std::upper_bound(edges_.begin(), edges_.end(), x) - edges_.begin() - 1, density_.size() - 1);
    return density_[i];
  }
  std::vector<double> breakpoints() const { return edges_; }

 private:
  std::vector<double> edges_, density_, cdf_;
};

using BasicTechnique1D = std::variant<UniformTechnique1D, TruncatedNormalTechnique1D, PiecewiseConstantTechnique1D>;

// Σ_k w_k p_k(x), weights normalised; one uniform picks the component.
class MixtureTechnique1D {
 public:
  using Sample = double;
  MixtureTechnique1D(std::vector<BasicTechnique1D> components, std::vector<double> weights)
      : components_(std::move(components)), weights_(std::move(weights)) {
    if (components_.size() != weights_.size() || components_.empty())
      throw std::invalid_argument("mixture: one weight per component");
    double total = 0.0;
    for (double w : weights_) total += w;
    for (double& w : weights_) w /= total;
  }
  std::optional<double> sample(Uniforms& u) const {
    double r = u.next();
    size_t k = 0;
    while (k + 1 < weights_.size() && r >= weights_[k]) r -= weights_[k++];
    return std::visit([&](const auto& c) { return c.sample(u); }, components_[k]);
  }
  double pdf(double x) const {
    double p = 0.0;
    for (size_t k = 0; k < components_.size(); ++k)
      p += weights_[k] * std::visit([&](const auto& c) { return c.pdf(x); }, components_[k]);
    return p;
  }
  std::vector<double> breakpoints() const {
    std::vector<double> b;
    for (const auto& c : components_) {
      const auto cb = std::visit([](const auto& cc) { return cc.breakpoints(); }, c);
      b.insert(b.end(), cb.begin(), cb.end());
    }
    return b;
  }

 private:
  std::vector<BasicTechnique1D> components_;
  std::vector<double> weights_;
};

// Any classical 1D technique (a value type; satisfies tb::Technique).
class Classical1D {
 public:
  using Sample = double;
  using Variant = std::variant<UniformTechnique1D, TruncatedNormalTechnique1D, PiecewiseConstantTechnique1D, MixtureTechnique1D>;
  template <class T>
  Classical1D(T t, std::string name = "") : v_(std::move(t)), name_(std::move(name)) {}

  std::optional<double> sample(Uniforms& u) const {
    return std::visit([&](const auto& t) { return t.sample(u); }, v_);
  }
  double pdf(double x) const {
    return std::visit([&](const auto& t) { return t.pdf(x); }, v_);
  }
  // Sorted, unique discontinuities of the density (support ends included).
  std::vector<double> breakpoints() const {
    auto b = std::visit([](const auto& t) { return t.breakpoints(); }, v_);
    std::sort(b.begin(), b.end());
    b.erase(std::unique(b.begin(), b.end()), b.end());
    return b;
  }
  const std::string& name() const { return name_; }

 private:
  Variant v_;
  std::string name_;
};

}  // namespace tb

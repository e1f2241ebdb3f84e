// Proposals on R^N (Lebesgue measure; densities are products of normal densities):
//  - GaussianRandomWalk: y = x + sigma z, symmetric;
//  - IndependentGaussian: y ~ N(mu, sigma^2 I), independent of x (asymmetric in the MH sense);
//  - RegionalRandomWalk: y = x + sigma_{r(x)} z with the scale chosen by the region of x, the
//    state-dependent proposal of Otsu et al., Eq. 2-3 (T(x -> .) = sum_k 1_{P_k}(x) T_k(x -> .));
//    not symmetric across region boundaries, so its Hastings ratio does not cancel;
//  - StatedDensity: samples with one proposal, states the density of another (negative controls).
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "analytic/mcmc/normal.h"
#include "estimators/mcmc/concepts.h"

namespace tb::mcmc {

template <size_t N>
class GaussianRandomWalk {
 public:
  using State = Point<N>;
  explicit GaussianRandomWalk(double sigma) : sigma_(sigma) {}
  double sigma() const { return sigma_; }
  void set_sigma(double s) { sigma_ = s; }
  std::optional<State> propose(const State& x, Uniforms& u) const {
    State y = x;
    for (size_t d = 0; d < N; ++d) y[d] += sigma_ * standard_normal(u);
    return y;
  }
  double density(const State& x, const State& y) const {
    double p = 1.0;
    for (size_t d = 0; d < N; ++d) p *= normal_pdf(y[d], x[d], sigma_);
    return p;
  }

 private:
  double sigma_;
};

template <size_t N>
class IndependentGaussian {
 public:
  using State = Point<N>;
  IndependentGaussian(Point<N> mu, double sigma) : mu_(mu), sigma_(sigma) {}
  std::optional<State> propose(const State&, Uniforms& u) const {
    State y{};
    for (size_t d = 0; d < N; ++d) y[d] = mu_[d] + sigma_ * standard_normal(u);
    return y;
  }
  double density(const State&, const State& y) const {
    double p = 1.0;
    for (size_t d = 0; d < N; ++d) p *= normal_pdf(y[d], mu_[d], sigma_);
    return p;
  }

 private:
  Point<N> mu_;
  double sigma_;
};

// Regions are intervals of x[0] cut at `cuts` (sorted); region r uses sigmas[r].
template <size_t N>
class RegionalRandomWalk {
 public:
  using State = Point<N>;
  RegionalRandomWalk(std::vector<double> cuts, std::vector<double> sigmas)
      : cuts_(std::move(cuts)), sigmas_(std::move(sigmas)) {}
  int regions() const { return static_cast<int>(sigmas_.size()); }
  int region(const State& x) const {
    return static_cast<int>(std::upper_bound(cuts_.begin(), cuts_.end(), x[0]) - cuts_.begin());
  }
  double sigma(int r) const { return sigmas_[r]; }
  void set_sigma(int r, double s) { sigmas_[r] = s; }
  std::optional<State> propose(const State& x, Uniforms& u) const {
    return GaussianRandomWalk<N>(sigmas_[region(x)]).propose(x, u);
  }
  double density(const State& x, const State& y) const {
    return GaussianRandomWalk<N>(sigmas_[region(x)]).density(x, y);
  }

 private:
  std::vector<double> cuts_;
  std::vector<double> sigmas_;
};

// Draws from Sampler, states the density of Stated: a proposal whose density is wrong on purpose.
template <Proposal Sampler, Proposal Stated>
class StatedDensity {
 public:
  using State = typename Sampler::State;
  StatedDensity(Sampler s, Stated d) : s_(std::move(s)), d_(std::move(d)) {}
  std::optional<State> propose(const State& x, Uniforms& u) const { return s_.propose(x, u); }
  double density(const State& x, const State& y) const { return d_.density(x, y); }

 private:
  Sampler s_;
  Stated d_;
};

// Selection for a random walk (k = 0) mixed with an independent proposal (k = 1): the independent
// proposal is used more often far from the origin, c_1(x) = 0.15 near, 0.6 where |x0| > cut.
struct DistanceSelection {
  double cut = 2.0;
  template <class State>
  double operator()(int k, const State& x) const {
    const double c1 = std::abs(x[0]) > cut ? 0.6 : 0.15;
    return k == 1 ? c1 : 1.0 - c1;
  }
};

}  // namespace tb::mcmc

// Adaptation hooks: a per-region parameter updated from the acceptance probabilities observed in
// that region, with diminishing adaptation (Roberts & Rosenthal 2009, "Examples of adaptive MCMC",
// Sec. 3; Otsu et al., Sec. 4.3 and 5.3). The regional adaptive MLT of a later issue plugs its
// partitions into this interface.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <vector>

namespace tb::mcmc {

// An adapter owns one parameter per region; the chain reports the acceptance probability a(x -> y)
// of every proposal made from region r (Otsu et al., Algorithm 1, line 11).
template <class A>
concept RegionAdapter = requires(A& a, const A& ca, int region, double acceptance) {
  { ca.regions() } -> std::convertible_to<int>;
  { ca.parameter(region) } -> std::convertible_to<double>;
  { a.observe(region, acceptance) };
};

// Robbins-Monro adaptation of a proposal scale towards a target acceptance a* (Andrieu & Thoms
// 2008, Sec. 5; Otsu et al., Algorithm 1 and Eq. 4-6). Per region it averages the acceptance
// probability over L visits (Eq. 4), then updates lambda = log sigma^2 by
//   lambda <- lambda + gamma_n (a_hat - a*),   gamma_n = min(gamma_max, gamma_scale n^{-1/2})  (Eq. 6)
// This departs from Otsu et al.'s Eq. 5, which uses sgn(a_hat - a*): the Robbins-Monro step in
// the difference itself converges to the root rather than oscillating around it with step gamma_n.
// Both satisfy diminishing adaptation (gamma_n -> 0).
class RobbinsMonroScale {
 public:
  struct Options {
    double target_acceptance = 0.234;  // a*; Otsu et al. use 0.234 (Roberts et al. 1997)
    int batch = 100;                   // L, visits per update
    double gamma_max = 1.0;
    double gamma_scale = 1.0;
  };

  RobbinsMonroScale(int regions, double initial_sigma, Options o)
      : o_(o), lambda_(regions, std::log(initial_sigma * initial_sigma)), sum_(regions, 0.0), visits_(regions, 0),
        updates_(regions, 0) {}

  int regions() const { return static_cast<int>(lambda_.size()); }
  // sigma_r = sqrt(exp(lambda_r)) (Otsu et al., Algorithm 1, line 9).
  double parameter(int r) const { return std::sqrt(std::exp(lambda_[r])); }
  double log_sigma2(int r) const { return lambda_[r]; }
  int updates(int r) const { return updates_[r]; }
  // gamma for the n-th update (n >= 1), Eq. 6.
  double gamma(int n) const { return std::min(o_.gamma_max, o_.gamma_scale / std::sqrt(static_cast<double>(n))); }

  void observe(int r, double acceptance) {
    sum_[r] += acceptance;
    if (++visits_[r] < o_.batch) return;
    const double a_hat = sum_[r] / visits_[r];  // Eq. 4
    ++updates_[r];
    lambda_[r] += gamma(updates_[r]) * (a_hat - o_.target_acceptance);
    sum_[r] = 0.0;
    visits_[r] = 0;
  }

 private:
  Options o_;
  std::vector<double> lambda_, sum_;
  std::vector<int> visits_, updates_;
};

static_assert(RegionAdapter<RobbinsMonroScale>);

}  // namespace tb::mcmc

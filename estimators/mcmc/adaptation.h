// Regional adaptation of a proposal scale (Roberts & Rosenthal 2009, "Examples of adaptive MCMC",
// Sec. 3; Otsu et al., Sec. 4.3-5.3 and Algorithm 1). Per region k of a partition (partition.h)
// the chain reports the acceptance probability a(x -> y) of every proposal made from a state x in
// region k (Algorithm 1, line 11); every L visits the region's lambda_k = log sigma_k^2 moves by
// gamma_j times a direction computed from the batch mean a_hat_k:
//   a_hat_k = A_k / L                                              (Eq. 4, line 14)
//   gamma_j = min(gamma_max, gamma_scale j^{-1/2})                 (Eq. 6, line 15)
//   lambda_k <- max(lambda_min, lambda_k + gamma_j d(a_hat_k, a*)) (Eq. 5, line 16; Sec. 8.1 clamp)
//   sigma_k = exp(lambda_k / 2)                                    (line 9)
// The direction d is a named update rule: OtsuSignUpdate, d = sgn(a_hat - a*) (Eq. 5, the
// default), or RobbinsMonroDifferenceUpdate, d = a_hat - a* (Andrieu & Thoms 2008, Sec. 5).
// Both diminish (gamma_j -> 0), so the adaptation vanishes (Roberts & Rosenthal 2009, Sec. 2).
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <string>
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

// The constants of Algorithm 1; defaults of Otsu et al., Sec. 8.1 (their a* = 0.234 is the
// Roberts et al. 1997 optimum in high dimension; 0.5 is closer to the 1D-2D optimum, 0.44).
struct AdaptationOptions {
  double lambda0 = 1.0;             // initial lambda = log sigma^2 (line 3)
  int batch = 10;                   // L, visits per update (line 13)
  double gamma_max = 1.0;           // Eq. 6
  double gamma_scale = 5.0;         // Eq. 6
  double target_acceptance = 0.5;   // a*
  double lambda_min = -30.0;        // Sec. 8.1: lambda is clamped from below
};

// Eq. 5: lambda <- lambda + gamma sgn(a_hat - a*). The default.
struct OtsuSignUpdate {
  static std::string name() { return "sign"; }
  static double gamma(const AdaptationOptions& o, int j) {
    return std::min(o.gamma_max, o.gamma_scale / std::sqrt(static_cast<double>(j)));  // Eq. 6
  }
  static double direction(double a_hat, double a_star) {
    return a_hat > a_star ? 1.0 : (a_hat < a_star ? -1.0 : 0.0);
  }
};

// Robbins-Monro: lambda <- lambda + gamma (a_hat - a*). Converges to the root rather than
// oscillating around it with step gamma_j; same schedule (Eq. 6).
struct RobbinsMonroDifferenceUpdate {
  static std::string name() { return "difference"; }
  static double gamma(const AdaptationOptions& o, int j) { return OtsuSignUpdate::gamma(o, j); }
  static double direction(double a_hat, double a_star) { return a_hat - a_star; }
};

template <class U>
concept AdaptationUpdate = requires(const AdaptationOptions& o, int j, double a) {
  { U::name() } -> std::convertible_to<std::string>;
  { U::gamma(o, j) } -> std::convertible_to<double>;
  { U::direction(a, a) } -> std::convertible_to<double>;
};

// One parameter update, kept in the record (diminishing-adaptation checks read it).
struct AdaptationUpdateRecord {
  int region = 0;
  int j = 0;              // n_k: the update's index in its region, from 1
  double a_hat = 0.0;     // Eq. 4
  double gamma = 0.0;     // Eq. 6
  double lambda = 0.0;    // lambda_k after the update
};

// Algorithm 1's per-region state: lambda_k, i_k (visits), A_k (accumulated acceptance), n_k.
template <AdaptationUpdate Update = OtsuSignUpdate>
class RegionalAdaptation {
 public:
  using UpdateRule = Update;
  RegionalAdaptation(int regions, AdaptationOptions o, bool keep_record = false)
      : o_(o), keep_record_(keep_record), lambda_(regions, o.lambda0), sum_(regions, 0.0), visits_(regions, 0),
        updates_(regions, 0) {}

  int regions() const { return static_cast<int>(lambda_.size()); }
  const AdaptationOptions& options() const { return o_; }
  // sigma_k = sqrt(exp(lambda_k)) (Algorithm 1, line 9).
  double parameter(int r) const { return std::exp(0.5 * lambda_[r]); }
  double sigma(int r) const { return parameter(r); }
  double lambda(int r) const { return lambda_[r]; }
  double log_sigma2(int r) const { return lambda_[r]; }
  void set_lambda(int r, double l) { lambda_[r] = l; }
  int updates(int r) const { return updates_[r]; }
  double gamma(int j) const { return Update::gamma(o_, j); }
  const std::vector<AdaptationUpdateRecord>& record() const { return record_; }

  // Algorithm 1, lines 11-18. The update fires on the L-th visit, so a_hat is the mean of exactly
  // L acceptances (line 14 divides by L; line 13's "i_k > L" would average L + 1 of them).
  void observe(int r, double acceptance) {
    sum_[r] += acceptance;                       // line 11
    if (++visits_[r] < o_.batch) return;         // lines 12-13
    const double a_hat = sum_[r] / o_.batch;     // line 14, Eq. 4
    const int j = ++updates_[r];
    const double g = Update::gamma(o_, j);       // line 15, Eq. 6
    lambda_[r] = std::max(o_.lambda_min, lambda_[r] + g * Update::direction(a_hat, o_.target_acceptance));  // line 16
    sum_[r] = 0.0;                               // line 17
    visits_[r] = 0;
    if (keep_record_) record_.push_back({r, j, a_hat, g, lambda_[r]});
  }

 private:
  AdaptationOptions o_;
  bool keep_record_;
  std::vector<double> lambda_, sum_;
  std::vector<int> visits_, updates_;
  std::vector<AdaptationUpdateRecord> record_;
};

using OtsuAdaptation = RegionalAdaptation<OtsuSignUpdate>;
using RobbinsMonroAdaptation = RegionalAdaptation<RobbinsMonroDifferenceUpdate>;

// The difference form with the constructor of its first version: initial sigma instead of
// lambda0, and its own defaults (a* = 0.234, L = 100, gamma_scale = 1).
class RobbinsMonroScale : public RobbinsMonroAdaptation {
 public:
  struct Options {
    double target_acceptance = 0.234;
    int batch = 100;
    double gamma_max = 1.0;
    double gamma_scale = 1.0;
  };
  RobbinsMonroScale(int regions, double initial_sigma, Options o)
      : RobbinsMonroAdaptation(regions, {.lambda0 = std::log(initial_sigma * initial_sigma),
                                         .batch = o.batch,
                                         .gamma_max = o.gamma_max,
                                         .gamma_scale = o.gamma_scale,
                                         .target_acceptance = o.target_acceptance}) {}
};

static_assert(RegionAdapter<OtsuAdaptation>);
static_assert(RegionAdapter<RobbinsMonroScale>);

}  // namespace tb::mcmc

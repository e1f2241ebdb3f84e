// Finite-difference checker of an analytic Jacobian of f: R^n -> R^m (docs/validation.md C), for
// path-space Jacobians, half-vector maps, reversible-jump maps and every hand-derived derivative.
//
// At each configuration x it computes:
//  * central differences with h_i = eps^(1/3) * max(1, |x_i|) (truncation O(h^2) balances rounding
//    O(eps/h) at this h; Press et al., Numerical Recipes 3rd ed., Sec. 5.7), and again
//    with h_i/2; if the two disagree by more than `discontinuity_tolerance` the configuration
//    straddles a discontinuity or kink and is skipped and counted, never failed or passed;
//  * relative error  err = max_ij |J_fd - J|_ij / max(1, max_ij |J_ij|)  (a max-norm over the whole
//    matrix with a floor of 1, so tiny entries of a large Jacobian are not judged relative to
//    themselves);
//  * Ridders' extrapolation of the same derivatives through Ceres
//    (ceres::DynamicNumericDiffCostFunction with ceres::RIDDERS), same error measure;
//  * a Taylor test along a seeded random unit direction d: r(h) = |f(x + h d) - f(x) - h J d| for
//    h = h0 2^-k; the least-squares slope of log r against log h must be 2 +- slope_tolerance
//    (points where r is at the rounding floor are dropped; if fewer than 3 remain, f is locally
//    linear along d and the slope is reported as NaN, not failed; `taylor_fit_points` > 0 fits only
//    that many of the smallest remaining steps, the most asymptotic part of r(h)). A direction along
//    which the quadratic term nearly vanishes shows the cubic one (slope towards 3) over the whole
//    range; with `taylor_directions` > 1 further seeded directions are tried and the configuration
//    passes when one of them gives 2 +- slope_tolerance. A wrong J still fails: its remainder has a
//    linear term (J_true - J) d, which is non-zero for almost every d, so every direction's slope
//    falls towards 1;
//  * the 2-norm condition number of J (Eigen JacobiSVD), reported.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace tb::stats {

using VectorFunction = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;
using JacobianFunction = std::function<Eigen::MatrixXd(const Eigen::VectorXd&)>;  // m x n

struct FdOptions {
  double tolerance = 1e-6;               // pass: central-difference relative error below this
  double discontinuity_tolerance = 1e-4; // skip when |D_h - D_{h/2}| (relative, as err) exceeds this
  bool ridders = true;                   // cross-check with Ridders' extrapolation (Ceres)
  double ridders_tolerance = 1e-6;       // pass: Ridders relative error below this
  double ridders_initial_step = 1e-2;    // Ridders' first step, times max(1, |x_i|) (the Ceres default)
  bool taylor = true;                    // run the Taylor test
  double slope_tolerance = 0.1;          // pass: |slope - 2| <= this
  double taylor_h0 = 1e-2;               // largest Taylor step (times max(1, |x|_inf))
  int taylor_steps = 8;                  // number of halvings
  int taylor_fit_points = 0;             // > 0: fit only this many smallest steps above the floor
  int taylor_directions = 1;             // directions tried (see the header comment)
  uint64_t seed = 1;                     // for the Taylor directions
};

struct FdPointResult {
  double rel_error = 0.0;          // central differences vs analytic
  double ridders_rel_error = 0.0;  // Ridders vs analytic (0 when disabled)
  double step_disagreement = 0.0;  // h vs h/2, same measure
  double taylor_slope = 0.0;       // NaN when f is linear along the direction
  int taylor_directions_used = 0;  // directions drawn until one passed (or all of them)
  double condition_number = 0.0;   // sigma_max / sigma_min of J (inf when rank deficient)
  bool skipped = false;            // discontinuity suspected
  bool nonfinite = false;          // f or J produced NaN / Inf (counts as a failure)
  bool passed = false;
};

struct FdResult {
  bool passed = false;              // every non-skipped configuration passed, at least one checked
  int64_t checked = 0;              // configurations that were compared
  int64_t skipped = 0;              // discontinuities suspected
  int64_t failed = 0;
  int64_t nonfinite = 0;
  double worst_rel_error = 0.0;
  int64_t worst_index = -1;         // configuration index of worst_rel_error (reproducer)
  double worst_ridders_rel_error = 0.0;
  double worst_taylor_slope_deviation = 0.0;  // max |slope - 2| over configurations with a slope
  int64_t worst_taylor_index = -1;
  double max_condition_number = 0.0;
  double median_condition_number = 0.0;
  int64_t first_failure_index = -1;
  std::string message;              // one line summary
  std::vector<FdPointResult> points;  // per configuration, in index order
};

// Checks J against f at one configuration. `index` seeds the Taylor direction.
FdPointResult check_jacobian_at(const VectorFunction& f, const JacobianFunction& jac, const Eigen::VectorXd& x,
                                const FdOptions& options = {}, uint64_t index = 0);

// Checks configurations x = config(i), i = 0..count-1, in parallel (deterministic for any thread
// count as long as config(i) is a pure function of i).
FdResult check_jacobian(const VectorFunction& f, const JacobianFunction& jac,
                        const std::function<Eigen::VectorXd(int64_t)>& config, int64_t count,
                        const FdOptions& options = {});

}  // namespace tb::stats

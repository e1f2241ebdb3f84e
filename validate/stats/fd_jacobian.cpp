#include "validate/stats/fd_jacobian.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <ceres/dynamic_numeric_diff_cost_function.h>
#include <ceres/numeric_diff_options.h>
#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"

namespace tb::stats {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

bool all_finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

// Central differences, column by column: (f(x + h e_i) - f(x - h e_i)) / (2 h_i),
// h_i = scale * eps^(1/3) * max(1, |x_i|); the step is made exactly representable by
// computing it as (x + h) - x.
Eigen::MatrixXd central_differences(const VectorFunction& f, const Eigen::VectorXd& x, Eigen::Index m, double scale) {
  const Eigen::Index n = x.size();
  Eigen::MatrixXd d(m, n);
  const double base = std::cbrt(kEps);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double h0 = scale * base * std::max(1.0, std::fabs(x[i]));
    Eigen::VectorXd xp = x, xm = x;
    xp[i] = x[i] + h0;
    xm[i] = x[i] - h0;
    const double h = xp[i] - xm[i];
    d.col(i) = (f(xp) - f(xm)) / h;
  }
  return d;
}

// Max-norm relative error with a floor of 1 (see the header).
double relative_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& reference) {
  const double scale = std::max(1.0, reference.cwiseAbs().maxCoeff());
  return (a - reference).cwiseAbs().maxCoeff() / scale;
}

struct RiddersFunctor {
  const VectorFunction* f;
  Eigen::Index n, m;
  bool operator()(double const* const* parameters, double* residuals) const {
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(parameters[0], n);
    const Eigen::VectorXd y = (*f)(x);
    if (y.size() != m || !y.allFinite()) return false;
    Eigen::Map<Eigen::VectorXd>(residuals, m) = y;
    return true;
  }
};

// Ridders' extrapolation of the Jacobian through Ceres' numeric differentiation.
bool ridders_jacobian(const VectorFunction& f, const Eigen::VectorXd& x, Eigen::Index m, double initial_step,
                      Eigen::MatrixXd& jac) {
  ceres::NumericDiffOptions options;  // Ceres defaults (shrink 2, <= 10 steps) but the first step
  options.ridders_relative_initial_step_size = initial_step;
  auto* functor = new RiddersFunctor{&f, x.size(), m};
  ceres::DynamicNumericDiffCostFunction<RiddersFunctor, ceres::RIDDERS> cost(functor, ceres::TAKE_OWNERSHIP, options);
  cost.AddParameterBlock(static_cast<int>(x.size()));
  cost.SetNumResiduals(static_cast<int>(m));
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> j(m, x.size());
  Eigen::VectorXd residuals(m);
  const double* params[] = {x.data()};
  double* jacobians[] = {j.data()};
  if (!cost.Evaluate(params, residuals.data(), jacobians)) return false;
  jac = j;
  return jac.allFinite();
}

// Taylor test along a unit direction d: slope of log r(h) against log h by least squares.
double taylor_slope(const VectorFunction& f, const Eigen::VectorXd& x, const Eigen::VectorXd& fx,
                    const Eigen::MatrixXd& jac, const Eigen::VectorXd& d, const FdOptions& o) {
  const Eigen::VectorXd jd = jac * d;
  const double h0 = o.taylor_h0 * std::max(1.0, x.cwiseAbs().maxCoeff());
  std::vector<double> lh, lr;
  for (int k = 0; k < o.taylor_steps; ++k) {
    const double h = std::ldexp(h0, -k);
    const Eigen::VectorXd fh = f(x + h * d);
    const double r = (fh - fx - h * jd).norm();
    // Rounding floor of the remainder: a few thousand ulps of the terms it is computed from.
    const double floor = 1e4 * kEps * (fx.norm() + fh.norm() + h * jd.norm());
    if (std::isfinite(r) && r > floor) {
      lh.push_back(std::log(h));
      lr.push_back(std::log(r));
    }
  }
  if (lh.size() < 3) return std::numeric_limits<double>::quiet_NaN();  // linear along d
  if (o.taylor_fit_points >= 3 && lh.size() > static_cast<size_t>(o.taylor_fit_points)) {
    lh.erase(lh.begin(), lh.end() - o.taylor_fit_points);
    lr.erase(lr.begin(), lr.end() - o.taylor_fit_points);
  }
  const double n = static_cast<double>(lh.size());
  double mx = 0, my = 0;
  for (size_t i = 0; i < lh.size(); ++i) mx += lh[i] / n, my += lr[i] / n;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < lh.size(); ++i) sxy += (lh[i] - mx) * (lr[i] - my), sxx += (lh[i] - mx) * (lh[i] - mx);
  return sxy / sxx;
}

}  // namespace

FdPointResult check_jacobian_at(const VectorFunction& f, const JacobianFunction& jac_fn, const Eigen::VectorXd& x,
                                const FdOptions& o, uint64_t index) {
  FdPointResult r;
  const Eigen::VectorXd fx = f(x);
  const Eigen::MatrixXd jac = jac_fn(x);
  if (!fx.allFinite() || !all_finite(jac) || jac.rows() != fx.size() || jac.cols() != x.size()) {
    r.nonfinite = true;
    return r;
  }
  const Eigen::Index m = fx.size();
  const Eigen::MatrixXd d1 = central_differences(f, x, m, 1.0);
  const Eigen::MatrixXd d2 = central_differences(f, x, m, 0.5);
  if (!all_finite(d1) || !all_finite(d2)) {
    // f is finite at x but not a step away: treat as a discontinuity (a boundary of the domain).
    r.skipped = true;
    return r;
  }
  r.step_disagreement = relative_error(d1, d2);
  if (r.step_disagreement > o.discontinuity_tolerance) {
    r.skipped = true;
    return r;
  }
  r.rel_error = relative_error(d2, jac);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(jac);
  const auto& s = svd.singularValues();
  r.condition_number = s.size() == 0 ? 1.0
                       : s[s.size() - 1] > 0.0 ? s[0] / s[s.size() - 1]
                                               : std::numeric_limits<double>::infinity();
  bool ok = r.rel_error < o.tolerance;
  if (o.ridders) {
    Eigen::MatrixXd jr;
    if (ridders_jacobian(f, x, m, o.ridders_initial_step, jr)) {
      r.ridders_rel_error = relative_error(jr, jac);
    } else {
      r.ridders_rel_error = std::numeric_limits<double>::infinity();
    }
    ok = ok && r.ridders_rel_error < o.ridders_tolerance;
  }
  if (o.taylor) {
    Rng rng = Rng::for_sample(o.seed, hash_string("fd_jacobian.taylor"), index);
    bool slope_ok = false;
    for (int k = 0; k < std::max(1, o.taylor_directions) && !slope_ok; ++k) {
      Eigen::VectorXd d(x.size());
      for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = 2.0 * rng.uniform() - 1.0;
      if (d.norm() == 0.0) d[0] = 1.0;
      d.normalize();
      const double slope = taylor_slope(f, x, fx, jac, d, o);
      // Report the first direction's slope unless a later one passes.
      if (k == 0 || std::fabs(slope - 2.0) <= o.slope_tolerance) r.taylor_slope = slope;
      r.taylor_directions_used = k + 1;
      slope_ok = std::isnan(slope) || std::fabs(slope - 2.0) <= o.slope_tolerance;
    }
    ok = ok && slope_ok;
  }
  r.passed = ok;
  return r;
}

FdResult check_jacobian(const VectorFunction& f, const JacobianFunction& jac,
                        const std::function<Eigen::VectorXd(int64_t)>& config, int64_t count, const FdOptions& o) {
  std::vector<FdPointResult> points(static_cast<size_t>(std::max<int64_t>(count, 0)));
  parallel_for(points.size(), [&](size_t i) {
    points[i] = check_jacobian_at(f, jac, config(static_cast<int64_t>(i)), o, static_cast<uint64_t>(i));
  });
  FdResult r;
  std::vector<double> conditions;
  for (size_t i = 0; i < points.size(); ++i) {
    const FdPointResult& p = points[i];
    const auto idx = static_cast<int64_t>(i);
    if (p.nonfinite) {
      ++r.nonfinite;
      ++r.failed;
      if (r.first_failure_index < 0) r.first_failure_index = idx;
      continue;
    }
    if (p.skipped) {
      ++r.skipped;
      continue;
    }
    ++r.checked;
    if (!p.passed) {
      ++r.failed;
      if (r.first_failure_index < 0) r.first_failure_index = idx;
    }
    if (p.rel_error > r.worst_rel_error || r.worst_index < 0) {
      r.worst_rel_error = p.rel_error;
      r.worst_index = idx;
    }
    r.worst_ridders_rel_error = std::max(r.worst_ridders_rel_error, p.ridders_rel_error);
    if (!std::isnan(p.taylor_slope) && o.taylor) {
      const double dev = std::fabs(p.taylor_slope - 2.0);
      if (dev > r.worst_taylor_slope_deviation || r.worst_taylor_index < 0) {
        r.worst_taylor_slope_deviation = dev;
        r.worst_taylor_index = idx;
      }
    }
    conditions.push_back(p.condition_number);
  }
  if (!conditions.empty()) {
    std::sort(conditions.begin(), conditions.end());
    r.max_condition_number = conditions.back();
    r.median_condition_number = conditions[conditions.size() / 2];
  }
  r.passed = r.failed == 0 && r.checked > 0;
  r.message = fmt::format(
      "{} configurations: {} checked, {} skipped (h vs h/2 disagree), {} failed ({} non-finite); worst rel. "
      "error {:.3g} at #{}, Ridders {:.3g}, max |Taylor slope - 2| {:.3g}, cond(J) median {:.3g} max {:.3g}",
      count, r.checked, r.skipped, r.failed, r.nonfinite, r.worst_rel_error, r.worst_index, r.worst_ridders_rel_error,
      r.worst_taylor_slope_deviation, r.median_condition_number, r.max_condition_number);
  r.points = std::move(points);
  return r;
}

}  // namespace tb::stats

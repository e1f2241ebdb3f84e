#include "validate/stats/convergence_fit.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <ceres/covariance.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb::stats {
namespace {

// Whitened residual of ln RMSE = ln C - alpha ln x (see the header).
struct PowerLawResidual {
  double log_x, log_rmse, weight;
  template <class T>
  bool operator()(const T* p, T* r) const {
    r[0] = (T(log_rmse) - p[0] + p[1] * log_x) * weight;
    return true;
  }
};

// Whitened residual of ln RMSE = 0.5 ln(C^2 x^(-2 alpha) + beta), p = (ln C, alpha, beta).
struct FloorResidual {
  double log_x, log_rmse, weight;
  template <class T>
  bool operator()(const T* p, T* r) const {
    T model2 = exp(2.0 * (p[0] - p[1] * log_x)) + p[2];
    // Outside the model's domain (beta < -C^2 N^(-2 alpha)) the residual is made huge rather than
    // invalid, so Ceres rejects the step as unsuccessful and shrinks its radius (returning false
    // counts as an invalid step, and five of those end the solve).
    if (!(model2 > T(1e-300))) model2 = T(1e-300);
    r[0] = (T(log_rmse) - 0.5 * log(model2)) * weight;
    return true;
  }
};

double whitening_weight(const ConvergencePoint& p) { return std::sqrt(2.0 * static_cast<double>(p.replicates)); }

void validate_points(std::span<const ConvergencePoint> pts, size_t min_points) {
  if (pts.size() < min_points) throw std::invalid_argument("convergence fit: too few points");
  for (const auto& p : pts)
    if (!(p.rmse > 0.0) || p.replicates < 1) throw std::invalid_argument("convergence fit: rmse <= 0 or no replicates");
}

ceres::Solver::Options solver_options() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 200;
  o.function_tolerance = 1e-14;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;
  o.logging_type = ceres::SILENT;
  return o;
}

// Covariance of the parameter block by dense SVD; false when Ceres cannot compute it.
bool covariance(ceres::Problem& problem, double* params, int size, std::vector<double>& cov) {
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;  // drop directions below min_reciprocal_condition_number
  ceres::Covariance c(co);
  std::vector<std::pair<const double*, const double*>> blocks = {{params, params}};
  if (!c.Compute(blocks, &problem)) return false;
  cov.assign(static_cast<size_t>(size * size), 0.0);
  return c.GetCovarianceBlock(params, params, cov.data());
}

// Interval multiplier: normal quantile when the residuals are white, otherwise the covariance is
// rescaled by the reduced chi-square and the Student t quantile with K - p dof is used.
double interval_quantile(double confidence, double chi2, int dof, const FitOptions& opt, double& p_value,
                         bool& rescaled) {
  const double upper = 1.0 - 0.5 * (1.0 - confidence);
  p_value = dof > 0 ? chi_squared_sf(chi2, dof) : 1.0;
  rescaled = dof > 0 && chi2 > dof && p_value < opt.whiteness_alpha;
  return rescaled ? students_t_quantile(upper, dof) : normal_quantile(upper);
}

PowerLawFit fit_xy(std::span<const ConvergencePoint> pts, const std::vector<double>& xs, const FitOptions& opt) {
  validate_points(pts, 3);
  const size_t k = pts.size();
  // Start from unweighted least squares.
  double mx = 0, my = 0;
  for (size_t i = 0; i < k; ++i) mx += std::log(xs[i]) / k, my += std::log(pts[i].rmse) / k;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < k; ++i) {
    const double dx = std::log(xs[i]) - mx;
    sxy += dx * (std::log(pts[i].rmse) - my);
    sxx += dx * dx;
  }
  if (!(sxx > 0.0)) throw std::invalid_argument("convergence fit: all x equal");
  const double alpha0 = -sxy / sxx;
  double p[2] = {my + alpha0 * mx, alpha0};  // ln C = mean(ln rmse) + alpha mean(ln x)

  ceres::Problem problem;
  std::vector<PowerLawResidual> residuals;
  for (size_t i = 0; i < k; ++i) {
    residuals.push_back({std::log(xs[i]), std::log(pts[i].rmse), whitening_weight(pts[i])});
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PowerLawResidual, 1, 2>(new PowerLawResidual(residuals.back())),
                             new ceres::HuberLoss(opt.huber_scale), p);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(), &problem, &summary);

  PowerLawFit fit;
  fit.confidence = opt.confidence;
  fit.points = static_cast<int64_t>(k);
  fit.converged = summary.IsSolutionUsable();
  fit.log_c = p[0];
  fit.alpha = p[1];
  double chi2 = 0.0;
  for (const auto& r : residuals) {
    double res = 0.0;
    r(p, &res);
    chi2 += res * res;
  }
  const int dof = static_cast<int>(k) - 2;
  fit.reduced_chi2 = dof > 0 ? chi2 / dof : 0.0;
  std::vector<double> cov;
  if (!covariance(problem, p, 2, cov)) {
    fit.converged = false;
    fit.alpha_std_error = fit.log_c_std_error = std::numeric_limits<double>::infinity();
  } else {
    const double q = interval_quantile(opt.confidence, chi2, dof, opt, fit.chi2_p_value, fit.rescaled);
    const double scale = fit.rescaled ? fit.reduced_chi2 : 1.0;
    fit.log_c_std_error = std::sqrt(cov[0] * scale);
    fit.alpha_std_error = std::sqrt(cov[3] * scale);
    fit.alpha_lo = fit.alpha - q * fit.alpha_std_error;
    fit.alpha_hi = fit.alpha + q * fit.alpha_std_error;
  }
  return fit;
}

struct FloorSolve {
  double p[3];
  double cost = std::numeric_limits<double>::infinity();
  bool usable = false;
};

}  // namespace

double PowerLawFit::predict(double n) const { return std::exp(log_c - alpha * std::log(n)); }

double FloorFit::predict(double n) const {
  return std::sqrt(std::max(0.0, std::exp(2.0 * (log_c - alpha * std::log(n))) + beta));
}

PowerLawFit fit_power_law(std::span<const ConvergencePoint> points, const FitOptions& options) {
  std::vector<double> xs;
  for (const auto& p : points) xs.push_back(p.n);
  return fit_xy(points, xs, options);
}

PowerLawFit fit_time_power_law(std::span<const ConvergencePoint> points, const FitOptions& options) {
  std::vector<double> xs;
  for (const auto& p : points) {
    if (!(p.seconds > 0.0)) throw std::invalid_argument("fit_time_power_law: non-positive time");
    xs.push_back(p.seconds);
  }
  return fit_xy(points, xs, options);
}

double efficiency(const ConvergencePoint& p) { return 1.0 / (p.rmse * p.rmse * p.seconds); }

FloorFit fit_power_law_with_floor(std::span<const ConvergencePoint> points, const FitOptions& options) {
  validate_points(points, 4);
  const PowerLawFit start = fit_power_law(points, options);
  double min_rmse = std::numeric_limits<double>::infinity();
  for (const auto& p : points) min_rmse = std::min(min_rmse, p.rmse);
  // Two starts (no floor, and a floor near the smallest RMSE); keep the lower cost.
  FloorSolve best;
  for (double beta0 : {0.0, 0.5 * min_rmse * min_rmse}) {
    auto solve = std::make_unique<FloorSolve>();
    solve->p[0] = start.log_c;
    solve->p[1] = start.alpha;
    solve->p[2] = beta0;
    ceres::Problem problem;
    for (const auto& pt : points)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FloorResidual, 1, 3>(new FloorResidual{
                                   std::log(pt.n), std::log(pt.rmse), whitening_weight(pt)}),
                               new ceres::HuberLoss(options.huber_scale), solve->p);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options(), &problem, &summary);
    if (summary.IsSolutionUsable() && summary.final_cost < best.cost) {
      best = *solve;
      best.cost = summary.final_cost;
      best.usable = true;
    }
  }
  FloorFit fit;
  fit.confidence = options.confidence;
  fit.converged = best.usable;
  if (!best.usable) return fit;
  // Rebuild the problem at the optimum for the covariance.
  ceres::Problem problem;
  double chi2 = 0.0;
  for (const auto& pt : points) {
    const FloorResidual res{std::log(pt.n), std::log(pt.rmse), whitening_weight(pt)};
    double r = 0.0;
    res(best.p, &r);
    chi2 += r * r;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FloorResidual, 1, 3>(new FloorResidual(res)),
                             new ceres::HuberLoss(options.huber_scale), best.p);
  }
  fit.log_c = best.p[0];
  fit.alpha = best.p[1];
  fit.beta = best.p[2];
  const int dof = static_cast<int>(points.size()) - 3;
  fit.reduced_chi2 = chi2 / dof;
  std::vector<double> cov;
  if (!covariance(problem, best.p, 3, cov)) {
    fit.converged = false;
    fit.alpha_std_error = fit.beta_std_error = fit.b_std_error = std::numeric_limits<double>::infinity();
    fit.beta_lo = -std::numeric_limits<double>::infinity();
    fit.beta_hi = std::numeric_limits<double>::infinity();
    fit.b = std::sqrt(std::max(fit.beta, 0.0));
    fit.b_hi = std::numeric_limits<double>::infinity();
    return fit;
  }
  const double q = interval_quantile(options.confidence, chi2, dof, options, fit.chi2_p_value, fit.rescaled);
  const double scale = fit.rescaled ? fit.reduced_chi2 : 1.0;
  fit.alpha_std_error = std::sqrt(cov[4] * scale);
  fit.beta_std_error = std::sqrt(cov[8] * scale);
  fit.beta_lo = fit.beta - q * fit.beta_std_error;
  fit.beta_hi = fit.beta + q * fit.beta_std_error;
  fit.b = std::sqrt(std::max(fit.beta, 0.0));
  fit.b_std_error = fit.b > 0.0 ? fit.beta_std_error / (2.0 * fit.b) : std::numeric_limits<double>::infinity();
  fit.b_lo = std::sqrt(std::max(fit.beta_lo, 0.0));
  fit.b_hi = std::sqrt(std::max(fit.beta_hi, 0.0));
  return fit;
}

std::vector<ConvergencePoint> measure_convergence(const Estimator& estimator, double truth,
                                                  const ConvergenceStudyOptions& o, int64_t* nonfinite) {
  if (o.log2_max < o.log2_min || o.replicates < 1) throw std::invalid_argument("measure_convergence: bad options");
  const size_t levels = static_cast<size_t>(o.log2_max - o.log2_min + 1);
  const size_t reps = static_cast<size_t>(o.replicates);
  std::vector<double> estimates(levels * reps), seconds(levels * reps);
  parallel_for(levels * reps, [&](size_t i) {
    const int k = o.log2_min + static_cast<int>(i / reps);
    const uint64_t r = i % reps;
    // A fresh seed for every (N, replicate): no sample prefix is shared across N.
    const uint64_t seed = hash_values(o.seed, o.key, static_cast<uint64_t>(k), r);
    const auto t0 = std::chrono::steady_clock::now();
    estimates[i] = estimator(int64_t{1} << k, seed);
    seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });
  std::vector<ConvergencePoint> points;
  int64_t bad = 0;
  for (size_t l = 0; l < levels; ++l) {
    Welford err, time;
    double sq = 0.0;
    for (size_t r = 0; r < reps; ++r) {
      const double e = estimates[l * reps + r] - truth;
      if (!std::isfinite(e)) {
        ++bad;
        continue;
      }
      err.add(e);
      time.add(seconds[l * reps + r]);
      sq += e * e;
    }
    ConvergencePoint p;
    p.n = std::ldexp(1.0, o.log2_min + static_cast<int>(l));
    p.replicates = err.count();
    p.rmse = p.replicates > 0 ? std::sqrt(sq / static_cast<double>(p.replicates)) : 0.0;
    p.seconds = time.mean();
    p.mean_error = err.mean();
    p.error_std_error = err.std_error();
    points.push_back(p);
  }
  if (nonfinite) *nonfinite = bad;
  return points;
}

ConvergenceStudy run_convergence_study(const Estimator& estimator, double truth, const ConvergenceStudyOptions& o) {
  ConvergenceStudy s;
  s.points = measure_convergence(estimator, truth, o, &s.nonfinite);
  s.fit = fit_power_law(s.points, o.fit);
  if (s.points.size() >= 4) s.floor_fit = fit_power_law_with_floor(s.points, o.fit);
  bool timed = true;
  for (const auto& p : s.points) timed = timed && p.seconds > 0.0;
  if (timed) s.time_fit = fit_time_power_law(s.points, o.fit);
  return s;
}

PlotSpec convergence_plot(const std::string& title, std::span<const ConvergencePoint> points, const PowerLawFit* fit,
                          const FloorFit* floor_fit) {
  PlotSpec plot;
  plot.title = title;
  plot.x_label = std::string("N");  // (move-assign: GCC 12 -Wrestrict false positive on char* assign)
  plot.y_label = std::string("RMSE");
  plot.log_x = plot.log_y = true;
  PlotSeries measured;
  measured.label = std::string("measured (+-1 SE)");
  measured.style = std::string("points");
  for (const auto& p : points) {
    measured.x.push_back(p.n);
    measured.y.push_back(p.rmse);
    // SE of RMSE_hat ~= RMSE / sqrt(2R) (delta method on MSE_hat ~ MSE chi2_R / R).
    measured.y_err.push_back(p.rmse / std::sqrt(2.0 * static_cast<double>(std::max<int64_t>(p.replicates, 1))));
  }
  plot.series.push_back(measured);
  if (fit != nullptr) {
    PlotSeries line;
    line.label = fmt::format("fit C N^-alpha, alpha = {:.4f} [{:.4f}, {:.4f}]", fit->alpha, fit->alpha_lo, fit->alpha_hi);
    line.style = std::string("lines");
    for (const auto& p : points) line.x.push_back(p.n), line.y.push_back(fit->predict(p.n));
    plot.series.push_back(line);
  }
  if (floor_fit != nullptr) {
    PlotSeries line;
    line.label = fmt::format("fit sqrt(C^2 N^-2alpha + b^2), b = {:.3g} [{:.3g}, {:.3g}]", floor_fit->b, floor_fit->b_lo,
                             floor_fit->b_hi);
    line.style = std::string("lines");
    for (const auto& p : points) line.x.push_back(p.n), line.y.push_back(floor_fit->predict(p.n));
    plot.series.push_back(line);
  }
  return plot;
}

}  // namespace tb::stats

// Convergence-rate fits with Ceres (docs/validation.md F).
//
// Model: RMSE(N) = C N^(-alpha). For R independent replicates at each N, with approximately normal
// errors, MSE_hat ~ MSE chi2_R / R, so Var(ln RMSE_hat) ~= 1 / (2R) (delta method); the whitened
// residual of point k is
//   r_k = (ln RMSE_k - ln C + alpha ln N_k) * sqrt(2 R_k).
// Ceres minimises sum rho(r_k^2) with a Huber loss (scale `huber_scale`, in standard deviations).
// The covariance of (ln C, alpha) comes from ceres::Covariance (DENSE_SVD). When the residuals
// are not white (heavy-tailed errors make Var(ln RMSE) = (kurtosis - 1) / (4R) > 1 / (2R), or the
// model is wrong), the covariance is multiplied by the reduced chi-square chi2 / (K - p) and the
// interval uses the Student t quantile with K - p dof; otherwise the normal quantile. "Not white"
// means chi2 is too large for chi2_{K-p}: upper-tail p-value below `whiteness_alpha` (0.01). A
// reduced chi-square of 1.4 over 11 dof is ordinary noise (its sd is sqrt(2/11) = 0.43) and does
// not widen the interval.
//
// Biased form (a consistent but biased estimator shows an error floor):
//   RMSE(N) = sqrt(C^2 N^(-2 alpha) + b^2),
// fitted in the parameters (ln C, alpha, beta = b^2) with beta allowed to be negative, so the
// interval of beta stays regular at b = 0; b = sqrt(max(beta, 0)), the interval of b is
// [sqrt(max(beta_lo, 0)), sqrt(max(beta_hi, 0))], and "b is consistent with 0" means beta_lo <= 0.
//
// Efficiency: the same power-law fit with wall time T in place of N (RMSE ~ C T^(-alpha)), and
// the per-point efficiency 1 / (MSE * T).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "validate/plot_spec.h"

namespace tb::stats {

struct ConvergencePoint {
  double n = 0.0;           // sample count N (or any cost measure)
  double rmse = 0.0;        // root mean squared error over the replicates at this N
  int64_t replicates = 0;   // R
  double seconds = 0.0;     // mean wall time of one replicate at this N
  double mean_error = 0.0;  // mean signed error (estimate - truth) over the replicates
  double error_std_error = 0.0;  // standard error of mean_error
};

struct PowerLawFit {
  bool converged = false;
  double alpha = 0.0;         // fitted exponent (positive for a converging estimator)
  double alpha_std_error = 0.0;
  double alpha_lo = 0.0, alpha_hi = 0.0;  // interval at `confidence`
  double log_c = 0.0;         // ln C
  double log_c_std_error = 0.0;
  double reduced_chi2 = 0.0;  // sum r_k^2 / (K - 2) of the whitened residuals
  double chi2_p_value = 1.0;  // upper-tail p-value of sum r_k^2 against chi2_{K-2}
  bool rescaled = false;      // covariance multiplied by reduced_chi2 (residuals not white)
  double confidence = 0.99;
  int64_t points = 0;
  double half_width() const { return 0.5 * (alpha_hi - alpha_lo); }
  double predict(double n) const;  // C n^(-alpha)
};

struct FloorFit {
  bool converged = false;
  double alpha = 0.0, alpha_std_error = 0.0;
  double log_c = 0.0;
  double beta = 0.0, beta_std_error = 0.0;  // beta = b^2
  double beta_lo = 0.0, beta_hi = 0.0;      // interval of beta at `confidence`
  double b = 0.0;                           // sqrt(max(beta, 0))
  double b_std_error = 0.0;                 // beta_std_error / (2 b) (delta method); inf when b = 0
  double b_lo = 0.0, b_hi = 0.0;            // sqrt(max(beta_lo/hi, 0))
  double reduced_chi2 = 0.0;
  double chi2_p_value = 1.0;  // against chi2_{K-3}
  bool rescaled = false;
  double confidence = 0.99;
  bool floor_detected() const { return beta_lo > 0.0; }  // interval of b excludes 0
  double predict(double n) const;  // sqrt(C^2 n^(-2 alpha) + beta), floored at 0 inside
};

struct FitOptions {
  double confidence = 0.99;
  double huber_scale = 3.0;  // Huber loss threshold in whitened residual units
  double whiteness_alpha = 0.01;  // rescale the covariance when P(chi2_{K-p} >= chi2) < this
};

// Fits ln RMSE = ln C - alpha ln N over the points (at least 3, all rmse > 0).
PowerLawFit fit_power_law(std::span<const ConvergencePoint> points, const FitOptions& options = {});
// Fits RMSE = sqrt(C^2 N^(-2 alpha) + b^2) (at least 4 points).
FloorFit fit_power_law_with_floor(std::span<const ConvergencePoint> points, const FitOptions& options = {});
// Fits RMSE = C T^(-alpha) over wall time T = seconds (efficiency; alpha ~ 0.5 for cost linear in N).
PowerLawFit fit_time_power_law(std::span<const ConvergencePoint> points, const FitOptions& options = {});
// 1 / (MSE * T) of one point.
double efficiency(const ConvergencePoint& p);

// Runs the replicate study: for N = 2^k, k = log2_min..log2_max, `replicates` independent runs of
// estimator(N, seed) each with its own seed hash_values(seed, key, k, r): no sample prefix is reused
// across N or replicates. Replicates run in parallel; results do not depend on the thread count.
using Estimator = std::function<double(int64_t n, uint64_t seed)>;
struct ConvergenceStudyOptions {
  int log2_min = 4;
  int log2_max = 16;
  int64_t replicates = 64;
  uint64_t seed = 1;
  uint64_t key = 0;  // e.g. hash_string(check name)
  FitOptions fit;
};
struct ConvergenceStudy {
  std::vector<ConvergencePoint> points;
  PowerLawFit fit;           // over N
  FloorFit floor_fit;        // over N, with an error floor
  PowerLawFit time_fit;      // over wall time
  int64_t nonfinite = 0;     // replicates whose estimate was NaN / Inf (excluded, reported)
};
std::vector<ConvergencePoint> measure_convergence(const Estimator& estimator, double truth,
                                                  const ConvergenceStudyOptions& options,
                                                  int64_t* nonfinite = nullptr);
ConvergenceStudy run_convergence_study(const Estimator& estimator, double truth,
                                       const ConvergenceStudyOptions& options = {});

// Log-log plot of RMSE against N: the measured points (with +-1 SE error bars of the RMSE,
// ~ RMSE / sqrt(2R)) and the fitted line(s).
PlotSpec convergence_plot(const std::string& title, std::span<const ConvergencePoint> points,
                          const PowerLawFit* fit, const FloorFit* floor_fit = nullptr);

}  // namespace tb::stats

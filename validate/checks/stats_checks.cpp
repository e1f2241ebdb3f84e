// Self-tests of the statistics engine (validate/stats/): the tests reject at their nominal rate
// under H0 and with their theoretical power under a known shift; the convergence fit recovers
// known rates and error floors; the finite-difference checker accepts a correct Jacobian and
// rejects a wrong one; the MCMC diagnostics recover a known autocorrelation time and flag
// unmixed chains. Every check here has a negative control (its own check or inside the run).
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/math.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/registry.h"
#include "validate/stats/ar1_process.h"
#include "validate/stats/convergence_fit.h"
#include "validate/stats/fd_jacobian.h"
#include "validate/stats/mcmc_diagnostics.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace tb {
namespace {

// ---- Rejection rates of the z and t tests -----------------------------------------------------

constexpr double kTestAlpha = 0.01;   // level of the z / t tests whose rejection rate is measured
constexpr double kCheckAlpha = 1e-3;  // level of the binomial test on the rejection counts
constexpr int64_t kMeanOf = 256;      // each repetition: the mean of 256 uniforms
const double kUniformSigma = std::sqrt(1.0 / 12.0);

struct RejectionCounts {
  int64_t reps = 0;
  int64_t z_rejections = 0, t_rejections = 0;
  std::vector<double> t_p_values;
};

// Repetition i: mean of kMeanOf uniforms plus `shift` standard errors, tested against 1/2 with
// the z test (known sigma, standard error multiplied by `se_factor`) and the t test (sample s).
RejectionCounts count_rejections(uint64_t seed, uint64_t key, int64_t reps, double shift, double se_factor) {
  RejectionCounts c;
  c.reps = reps;
  std::vector<char> z_rej(static_cast<size_t>(reps)), t_rej(static_cast<size_t>(reps));
  c.t_p_values.resize(static_cast<size_t>(reps));
  const double se = kUniformSigma / std::sqrt(static_cast<double>(kMeanOf));
  parallel_for(static_cast<size_t>(reps), [&](size_t i) {
    Rng rng = Rng::for_sample(seed, key, i);
    stats::Welford w;
    for (int64_t j = 0; j < kMeanOf; ++j) w.add(rng.uniform() + shift * se);
    z_rej[i] = stats::z_test(w.mean(), se * se_factor, 0.5).rejects(kTestAlpha);
    const stats::TestResult t = stats::one_sample_t_test(w, 0.5);
    t_rej[i] = t.rejects(kTestAlpha);
    c.t_p_values[i] = t.p_value;
  });
  for (size_t i = 0; i < z_rej.size(); ++i) c.z_rejections += z_rej[i], c.t_rejections += t_rej[i];
  return c;
}

PlotSpec p_value_histogram(const std::vector<double>& p, const std::string& title) {
  constexpr int kBins = 20;
  PlotSpec plot;
  plot.title = title;
  plot.x_label = std::string("p-value");
  plot.y_label = std::string("count");
  PlotSeries counts, expected;
  counts.label = std::string("observed");
  counts.style = std::string("boxes");
  expected.label = std::string("uniform expectation");
  expected.style = std::string("lines");
  std::vector<double> h(kBins, 0.0);
  for (double v : p) h[static_cast<size_t>(std::min(kBins - 1, static_cast<int>(v * kBins)))] += 1.0;
  for (int b = 0; b < kBins; ++b) {
    counts.x.push_back((b + 0.5) / kBins);
    counts.y.push_back(h[static_cast<size_t>(b)]);
    expected.x.push_back((b + 0.5) / kBins);
    expected.y.push_back(static_cast<double>(p.size()) / kBins);
  }
  plot.series = {counts, expected};
  return plot;
}

CheckResult run_null_rejection_rate(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.selftest.null_rejection_rate");
  const int64_t reps = ctx.size(1000, 10000);
  const RejectionCounts c = count_rejections(ctx.seed, key, reps, 0.0, 1.0);
  // Three tests on one sample of repetitions: Šidák over them.
  const double alpha = stats::sidak_alpha(kCheckAlpha, 3);
  const auto bz = stats::binomial_test(c.z_rejections, reps, kTestAlpha);
  const auto bt = stats::binomial_test(c.t_rejections, reps, kTestAlpha);
  const auto ks = stats::ks_test(c.t_p_values, [](double u) { return std::clamp(u, 0.0, 1.0); });
  CheckResult r;
  r.passed = !bz.rejects(alpha) && !bt.rejects(alpha) && !ks.rejects(alpha);
  r.statistic_name = "min p (binomial z, binomial t, KS of t p-values)";
  r.p_value = std::min({bz.p_value, bt.p_value, ks.p_value});
  r.statistic = r.p_value;
  r.alpha = alpha;
  r.samples = reps * kMeanOf;
  r.message = fmt::format(
      "under H0 (mean of {} uniforms, {} repetitions) at alpha {}: z test rejected {} (p = {:.3g}), t test {} "
      "(p = {:.3g}); t p-values uniform by KS (D = {:.4f}, p = {:.3g})",
      kMeanOf, reps, kTestAlpha, c.z_rejections, bz.p_value, c.t_rejections, bt.p_value, ks.statistic, ks.p_value);
  r.details = {{"repetitions", reps},
               {"samples_per_repetition", kMeanOf},
               {"test_alpha", kTestAlpha},
               {"expected_rejections", kTestAlpha * static_cast<double>(reps)},
               {"z_rejections", c.z_rejections},
               {"z_binomial_p", bz.p_value},
               {"t_rejections", c.t_rejections},
               {"t_binomial_p", bt.p_value},
               {"ks_t_p_values_D", ks.statistic},
               {"ks_t_p_values_p", ks.p_value},
               {"negative_control", "stats.selftest.negative_control"}};
  r.plots.push_back(p_value_histogram(c.t_p_values, "t-test p-values under H0 (should be uniform)"));
  return r;
}

CheckResult run_null_negative_control(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.selftest.negative_control");
  const int64_t reps = ctx.size(1000, 10000);
  // Broken: a standard error too small by sqrt(2) (e.g. a dropped factor of 2 in a variance).
  const RejectionCounts c = count_rejections(ctx.seed, key, reps, 0.0, 1.0 / std::sqrt(2.0));
  const auto bz = stats::binomial_test(c.z_rejections, reps, kTestAlpha);
  CheckResult r;
  r.passed = bz.rejects(kCheckAlpha);
  r.statistic_name = "z rejections";
  r.statistic = static_cast<double>(c.z_rejections);
  r.p_value = bz.p_value;
  r.alpha = kCheckAlpha;
  r.samples = reps * kMeanOf;
  r.message = fmt::format(
      "z test with a standard error too small by sqrt(2) rejected {} of {} at alpha {} (expected {:.0f} if it were "
      "right): binomial p = {:.3g}, {}",
      c.z_rejections, reps, kTestAlpha, kTestAlpha * static_cast<double>(reps), bz.p_value,
      r.passed ? "broken variant rejected" : "NOT rejected");
  r.details = {{"repetitions", reps}, {"z_rejections", c.z_rejections}, {"binomial_p", bz.p_value},
               {"expected_rate_of_broken", 2.0 * stats::normal_sf(stats::normal_quantile(1 - kTestAlpha / 2) / std::sqrt(2.0))}};
  return r;
}

CheckResult run_power(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.selftest.power");
  const int64_t reps = ctx.size(1000, 10000);
  constexpr double kDelta = 4.0;
  const RejectionCounts c = count_rejections(ctx.seed, key, reps, kDelta, 1.0);
  const double power_z = stats::z_test_power(kDelta, kTestAlpha);
  const double power_t = stats::t_test_power(kDelta, static_cast<double>(kMeanOf - 1), kTestAlpha);
  const double alpha = stats::sidak_alpha(kCheckAlpha, 2);
  const auto bz = stats::binomial_test(c.z_rejections, reps, power_z);
  const auto bt = stats::binomial_test(c.t_rejections, reps, power_t);
  const stats::Interval iz = stats::binomial_interval(c.z_rejections, reps, 1.0 - alpha);
  // Negative control inside the run: the same counts against the power claimed for a shift of
  // 3.5 standard errors (a wrong power formula) must be rejected.
  const auto wrong = stats::binomial_test(c.z_rejections, reps, stats::z_test_power(3.5, kTestAlpha));
  const bool control_rejected = wrong.rejects(kCheckAlpha);
  CheckResult r;
  r.passed = !bz.rejects(alpha) && !bt.rejects(alpha) && control_rejected;
  r.statistic_name = "z rejection rate";
  r.statistic = static_cast<double>(c.z_rejections) / static_cast<double>(reps);
  r.p_value = std::min(bz.p_value, bt.p_value);
  r.alpha = alpha;
  r.samples = reps * kMeanOf;
  r.message = fmt::format(
      "shift of {} SE: z test rejected {:.4f} (interval [{:.4f}, {:.4f}]) vs power {:.4f} (p = {:.3g}); t test {:.4f} "
      "vs non-central-t power {:.4f} (p = {:.3g}); control (power at 3.5 SE) {} (p = {:.3g})",
      kDelta, r.statistic, iz.lo, iz.hi, power_z, bz.p_value, static_cast<double>(c.t_rejections) / reps, power_t,
      bt.p_value, control_rejected ? "rejected" : "NOT rejected", wrong.p_value);
  r.details = {{"repetitions", reps},       {"delta_se", kDelta},          {"test_alpha", kTestAlpha},
               {"z_power", power_z},        {"z_rejections", c.z_rejections}, {"z_binomial_p", bz.p_value},
               {"t_power", power_t},        {"t_rejections", c.t_rejections}, {"t_binomial_p", bt.p_value},
               {"control_binomial_p", wrong.p_value}};
  return r;
}

TB_REGISTER_CHECK({.name = "stats.selftest.null_rejection_rate",
                   .description = "z and t tests of an unbiased mean reject at their nominal rate 0.01 (binomial test "
                                  "on the rejection count) and their p-values are uniform (KS)",
                   .kind = CheckKind::kStatistical,
                   .run = run_null_rejection_rate});
TB_REGISTER_CHECK({.name = "stats.selftest.negative_control",
                   .description = "A z test with a standard error too small by sqrt(2) is caught by the rejection-rate "
                                  "check (passes when rejected)",
                   .kind = CheckKind::kStatistical,
                   .run = run_null_negative_control});
TB_REGISTER_CHECK({.name = "stats.selftest.power",
                   .description = "At a shift of 4 standard errors the z and t tests reject at their theoretical "
                                  "power (normal and non-central t), and a wrong power is rejected",
                   .kind = CheckKind::kStatistical,
                   .run = run_power});

// ---- Convergence fits -------------------------------------------------------------------------

// Plain MC of integral_0^1 e^x dx = e - 1 with N uniforms, plus a constant bias.
stats::Estimator exp_integrand_mc(double bias) {
  return [bias](int64_t n, uint64_t seed) {
    Rng rng(seed);
    CompensatedSum s;
    for (int64_t i = 0; i < n; ++i) s += std::exp(rng.uniform());
    return s.value() / static_cast<double>(n) + bias;
  };
}
const double kExpIntegral = std::exp(1.0) - 1.0;

stats::ConvergenceStudyOptions study_options(const CheckContext& ctx, const char* name) {
  stats::ConvergenceStudyOptions o;
  o.log2_min = 4;
  o.log2_max = 16;
  o.replicates = ctx.size(64, 64);  // the 4x rerun uses 256
  o.seed = ctx.seed;
  o.key = hash_string(name);
  return o;
}

CheckResult run_mc_rate(const CheckContext& ctx) {
  constexpr double kMaxHalfWidth = 0.03;  // docs/validation.md F
  const auto o = study_options(ctx, "stats.convergence.mc_rate");
  const stats::ConvergenceStudy s = stats::run_convergence_study(exp_integrand_mc(0.0), kExpIntegral, o);
  // Negative control: an estimator that uses only sqrt(N) of its N samples converges at rate 1/4.
  auto wrong_o = o;
  wrong_o.key = hash_string("stats.convergence.mc_rate.negative_control");
  const auto sqrt_n = [](int64_t n, uint64_t seed) {
    return exp_integrand_mc(0.0)(static_cast<int64_t>(std::ceil(std::sqrt(static_cast<double>(n)))), seed);
  };
  const stats::PowerLawFit wrong = stats::fit_power_law(stats::measure_convergence(sqrt_n, kExpIntegral, wrong_o));
  const bool control_rejected = !(wrong.alpha_lo <= 0.5 && 0.5 <= wrong.alpha_hi);
  const auto& f = s.fit;
  CheckResult r;
  r.passed = f.converged && f.alpha_lo <= 0.5 && 0.5 <= f.alpha_hi && f.half_width() <= kMaxHalfWidth &&
             s.nonfinite == 0 && control_rejected;
  r.statistic_name = "alpha_hat";
  r.statistic = f.alpha;
  // p-value of H0: alpha = 1/2 with the fit's own standard error (t with K - 2 dof if rescaled).
  const double z_half = (f.alpha - 0.5) / f.alpha_std_error;
  r.p_value = f.rescaled ? stats::students_t_two_sided_p(z_half, static_cast<double>(f.points - 2))
                         : stats::normal_two_sided_p(z_half);
  r.alpha = 1.0 - f.confidence;
  r.samples = o.replicates * ((int64_t{2} << o.log2_max) - (int64_t{1} << o.log2_min));
  r.message = fmt::format(
      "plain MC of int e^x: alpha = {:.4f}, 99% interval [{:.4f}, {:.4f}] (half-width {:.4f} <= {}), reduced chi2 "
      "{:.2f}{}; time exponent {:.3f}; control (sqrt(N) samples) alpha = {:.4f} [{:.4f}, {:.4f}] {}",
      f.alpha, f.alpha_lo, f.alpha_hi, f.half_width(), kMaxHalfWidth, f.reduced_chi2, f.rescaled ? " (rescaled)" : "",
      s.time_fit.alpha, wrong.alpha, wrong.alpha_lo, wrong.alpha_hi, control_rejected ? "rejected" : "NOT rejected");
  r.details = {{"alpha", f.alpha},
               {"alpha_std_error", f.alpha_std_error},
               {"alpha_interval", {f.alpha_lo, f.alpha_hi}},
               {"C", std::exp(f.log_c)},
               {"C_expected", std::sqrt((std::exp(2.0) - 1.0) / 2.0 - kExpIntegral * kExpIntegral)},
               {"reduced_chi2", f.reduced_chi2},
               {"chi2_p_value", f.chi2_p_value},
               {"rescaled", f.rescaled},
               {"replicates", o.replicates},
               {"log2_N", {o.log2_min, o.log2_max}},
               {"time_alpha", s.time_fit.alpha},
               {"nonfinite", s.nonfinite},
               {"control_alpha", wrong.alpha},
               {"control_interval", {wrong.alpha_lo, wrong.alpha_hi}}};
  nlohmann::json pts = nlohmann::json::array();
  for (const auto& p : s.points)
    pts.push_back({{"N", p.n}, {"rmse", p.rmse}, {"seconds", p.seconds}, {"efficiency", stats::efficiency(p)}});
  r.details["points"] = pts;
  r.plots.push_back(stats::convergence_plot("plain MC of int_0^1 e^x dx: RMSE vs N", s.points, &s.fit));
  return r;
}

CheckResult run_biased_floor(const CheckContext& ctx) {
  // A bias of 5e-3 is 2.6 standard errors of the estimate at N = 2^16 (sigma = 0.49): the floor
  // dominates the last few points.
  constexpr double kBias = 5e-3;
  const auto o = study_options(ctx, "stats.convergence.biased_floor");
  auto o_unbiased = o;
  o_unbiased.key = hash_string("stats.convergence.biased_floor.unbiased");
  const auto biased = stats::run_convergence_study(exp_integrand_mc(kBias), kExpIntegral, o);
  const auto unbiased = stats::run_convergence_study(exp_integrand_mc(0.0), kExpIntegral, o_unbiased);
  const auto& fb = biased.floor_fit;
  const auto& fu = unbiased.floor_fit;
  const bool b_found = fb.converged && fb.floor_detected() && fb.b_lo <= kBias && kBias <= fb.b_hi;
  const bool u_clean = fu.converged && !fu.floor_detected();
  CheckResult r;
  r.passed = b_found && u_clean;
  r.statistic_name = "b (biased estimator)";
  r.statistic = fb.b;
  // p-values of H0: beta = 0 (no floor) for both estimators (normal approximation).
  const double p_biased = stats::z_test(fb.beta, fb.beta_std_error, 0.0).p_value;
  const double p_unbiased = stats::z_test(fu.beta, fu.beta_std_error, 0.0).p_value;
  r.p_value = p_unbiased;
  r.alpha = 1.0 - fb.confidence;
  r.samples = 2 * o.replicates * ((int64_t{2} << o.log2_max) - (int64_t{1} << o.log2_min));
  r.message = fmt::format(
      "biased (+{}): b = {:.3g}, 99% interval [{:.3g}, {:.3g}] ({}), alpha = {:.3f}; unbiased: b^2 = {:.3g} in [{:.3g}, "
      "{:.3g}] ({})",
      kBias, fb.b, fb.b_lo, fb.b_hi, b_found ? "excludes 0, contains the bias" : "WRONG", fb.alpha, fu.beta,
      fu.beta_lo, fu.beta_hi, u_clean ? "consistent with 0" : "floor claimed: WRONG");
  r.details = {{"bias", kBias},
               {"biased_no_floor_p", p_biased},
               {"unbiased_no_floor_p", p_unbiased},
               {"biased_b", fb.b},
               {"biased_b_std_error", fb.b_std_error},
               {"biased_b_interval", {fb.b_lo, fb.b_hi}},
               {"biased_alpha", fb.alpha},
               {"biased_reduced_chi2", fb.reduced_chi2},
               {"unbiased_beta", fu.beta},
               {"unbiased_beta_interval", {fu.beta_lo, fu.beta_hi}},
               {"unbiased_b", fu.b},
               {"unbiased_alpha", fu.alpha},
               {"unbiased_reduced_chi2", fu.reduced_chi2},
               {"replicates", o.replicates}};
  PlotSpec plot = stats::convergence_plot("MC of int e^x with a bias of 5e-3: error floor", biased.points, &biased.fit, &fb);
  r.plots.push_back(plot);
  return r;
}

TB_REGISTER_CHECK({.name = "stats.convergence.mc_rate",
                   .description = "The Ceres fit of ln RMSE against ln N recovers alpha = 1/2 for plain MC (99% interval "
                                  "contains 0.5, half-width <= 0.03) and rejects an estimator converging at 1/4",
                   .kind = CheckKind::kStatistical,
                   .run = run_mc_rate});
TB_REGISTER_CHECK({.name = "stats.convergence.biased_floor",
                   .description = "The error-floor fit sqrt(C^2 N^-2alpha + b^2) finds the bias of a biased estimator "
                                  "(interval excludes 0) and none for the unbiased one",
                   .kind = CheckKind::kStatistical,
                   .run = run_biased_floor});

// ---- Finite-difference Jacobians ----------------------------------------------------------------

Eigen::VectorXd spherical_to_cartesian(const Eigen::VectorXd& q) {
  const double r = q[0], theta = q[1], phi = q[2];
  Eigen::VectorXd p(3);
  p << r * std::sin(theta) * std::cos(phi), r * std::sin(theta) * std::sin(phi), r * std::cos(theta);
  return p;
}

// d(x, y, z) / d(r, theta, phi); `sign_error` flips dy/dphi (the negative control).
Eigen::MatrixXd spherical_jacobian(const Eigen::VectorXd& q, bool sign_error) {
  const double r = q[0], st = std::sin(q[1]), ct = std::cos(q[1]), sp = std::sin(q[2]), cp = std::cos(q[2]);
  Eigen::MatrixXd j(3, 3);
  j << st * cp, r * ct * cp, -r * st * sp,  //
      st * sp, r * ct * sp, (sign_error ? -1.0 : 1.0) * r * st * cp,  //
      ct, -r * st, 0.0;
  return j;
}

// Configuration i: r in [0.1, 10] (log-uniform), theta in [0.01, pi - 0.01], phi in [0, 2 pi).
std::function<Eigen::VectorXd(int64_t)> spherical_configs(uint64_t seed, uint64_t key) {
  return [seed, key](int64_t i) {
    Rng rng = Rng::for_sample(seed, key, static_cast<uint64_t>(i));
    Eigen::VectorXd q(3);
    q << 0.1 * std::pow(100.0, rng.uniform()), 0.01 + (kPi - 0.02) * rng.uniform(), 2.0 * kPi * rng.uniform();
    return q;
  };
}

PlotSpec fd_error_histogram(const stats::FdResult& res, const std::string& title) {
  PlotSpec plot;
  plot.title = title;
  plot.x_label = std::string("log10 relative error (central differences)");
  plot.y_label = std::string("configurations");
  PlotSeries s;
  s.label = std::string("count");
  s.style = std::string("boxes");
  constexpr int kLo = -16, kHi = 0;
  std::vector<double> h(kHi - kLo, 0.0);
  for (const auto& p : res.points) {
    if (p.skipped || p.nonfinite) continue;
    const double l = std::log10(std::max(p.rel_error, 1e-16));
    h[static_cast<size_t>(std::clamp(static_cast<int>(std::floor(l)) - kLo, 0, kHi - kLo - 1))] += 1.0;
  }
  for (int b = 0; b < kHi - kLo; ++b) s.x.push_back(kLo + b + 0.5), s.y.push_back(h[static_cast<size_t>(b)]);
  plot.series = {s};
  return plot;
}

nlohmann::json fd_details(const stats::FdResult& res, double tol) {
  return {{"checked", res.checked},
          {"skipped", res.skipped},
          {"failed", res.failed},
          {"nonfinite", res.nonfinite},
          {"tolerance", tol},
          {"worst_rel_error", res.worst_rel_error},
          {"worst_index", res.worst_index},
          {"worst_ridders_rel_error", res.worst_ridders_rel_error},
          {"worst_taylor_slope_deviation", res.worst_taylor_slope_deviation},
          {"worst_taylor_index", res.worst_taylor_index},
          {"median_condition_number", res.median_condition_number},
          {"max_condition_number", res.max_condition_number},
          {"first_failure_index", res.first_failure_index}};
}

CheckResult run_fd_spherical(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.fd.spherical_to_cartesian");
  const int64_t count = ctx.size(1000, 10000);
  stats::FdOptions opt;
  opt.seed = ctx.seed;
  const auto res = stats::check_jacobian(
      spherical_to_cartesian, [](const Eigen::VectorXd& q) { return spherical_jacobian(q, false); },
      spherical_configs(ctx.seed, key), count, opt);
  CheckResult r;
  r.passed = res.passed && res.worst_rel_error < opt.tolerance;
  r.statistic_name = "worst rel. error";
  r.statistic = res.worst_rel_error;
  r.samples = count;
  r.message = res.message;
  r.details = fd_details(res, opt.tolerance);
  r.plots.push_back(fd_error_histogram(res, "spherical -> Cartesian Jacobian: FD relative errors"));
  return r;
}

CheckResult run_fd_negative_control(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.fd.spherical_to_cartesian");  // the same configurations
  const int64_t count = ctx.size(1000, 10000);
  stats::FdOptions opt;
  opt.seed = ctx.seed;
  const auto res = stats::check_jacobian(
      spherical_to_cartesian, [](const Eigen::VectorXd& q) { return spherical_jacobian(q, true); },
      spherical_configs(ctx.seed, key), count, opt);
  CheckResult r;
  // dy/dphi = r sin(theta) cos(phi) vanishes only on a set of measure zero, so essentially every
  // configuration must fail; demand that the checker flags the sign error at 90% of them.
  r.passed = !res.passed && res.failed >= (9 * res.checked) / 10;
  r.statistic_name = "failed configurations";
  r.statistic = static_cast<double>(res.failed);
  r.samples = count;
  r.message = fmt::format("sign error in dy/dphi: {} ({})", r.passed ? "rejected" : "NOT rejected", res.message);
  r.details = fd_details(res, opt.tolerance);
  return r;
}

TB_REGISTER_CHECK({.name = "stats.fd.spherical_to_cartesian",
                   .description = "FD checker (central h and h/2, Ridders via Ceres, Taylor slope 2) accepts the "
                                  "analytic Jacobian of (r, theta, phi) -> (x, y, z)",
                   .kind = CheckKind::kDeterministic,
                   .run = run_fd_spherical});
TB_REGISTER_CHECK({.name = "stats.fd.negative_control",
                   .description = "FD checker rejects the spherical Jacobian with a sign error in dy/dphi (passes when "
                                  "rejected)",
                   .kind = CheckKind::kDeterministic,
                   .run = run_fd_negative_control});

// ---- MCMC diagnostics ---------------------------------------------------------------------------

CheckResult run_mcmc_diagnostics(const CheckContext& ctx) {
  const uint64_t key = hash_string("stats.mcmc.diagnostics");
  const int64_t chains = ctx.size(8, 32);
  const int64_t n = ctx.full ? (1 << 17) : (1 << 15);
  const std::vector<double> rhos = {-0.5, 0.5, 0.9};
  constexpr double kAlpha = 1e-3;
  const double alpha = stats::sidak_alpha(kAlpha, static_cast<int64_t>(rhos.size()));
  // Bias allowance: Geyer's truncation drops the autocorrelation tail beyond the lag where
  // rho^k falls to the noise level ~ sqrt(tau / n); for rho = 0.9 at n = 2^15 that tail is ~2.5%
  // of tau. 5% covers it with margin; the random part is judged by the spread over chains.
  constexpr double kBiasAllowance = 0.05;
  CheckResult r;
  r.passed = true;
  r.alpha = alpha;
  r.statistic_name = "max |tau_hat - tau| / tau";
  nlohmann::json per_rho = nlohmann::json::array();
  std::string msg;
  double worst = 0.0;
  for (size_t ri = 0; ri < rhos.size(); ++ri) {
    const double rho = rhos[ri];
    const double tau = stats::ar1_autocorrelation_time(rho);
    std::vector<double> taus(static_cast<size_t>(chains));
    parallel_for(static_cast<size_t>(chains), [&](size_t c) {
      Rng rng = Rng::for_sample(ctx.seed, key, ri * 1000 + c);
      taus[c] = stats::integrated_autocorrelation_time(stats::ar1_chain(rng, rho, n, 0.0, true)).tau;
    });
    stats::Welford w;
    for (double t : taus) w.add(t);
    const double z = stats::normal_quantile(1.0 - alpha / 2);
    const double tol = z * w.std_error() + kBiasAllowance * tau;
    const bool ok = std::fabs(w.mean() - tau) <= tol;
    r.passed = r.passed && ok;
    worst = std::max(worst, std::fabs(w.mean() - tau) / tau);
    per_rho.push_back({{"rho", rho}, {"tau", tau}, {"tau_hat_mean", w.mean()}, {"tau_hat_std_error", w.std_error()},
                       {"z_p_value_without_bias_allowance", stats::z_test(w.mean(), w.std_error(), tau).p_value},
                       {"tolerance", tol}, {"passed", ok}});
    msg += fmt::format("rho {}: tau {:.3f} est. {:.3f} +- {:.3f} (tol {:.3f}){}; ", rho, tau, w.mean(), w.std_error(),
                       tol, ok ? "" : " FAIL");
  }
  // Split R-hat: 4 stationary AR(0.9) chains mix; 4 AR(0.9999) chains (tau = 2e4, longer than
  // the chains' halves) started at +-5 do not.
  std::vector<std::vector<double>> mixed, unmixed;
  for (uint64_t c = 0; c < 4; ++c) {
    Rng a = Rng::for_sample(ctx.seed, key, 100000 + c);
    mixed.push_back(stats::ar1_chain(a, 0.9, n, 0.0, true));
    Rng b = Rng::for_sample(ctx.seed, key, 200000 + c);
    unmixed.push_back(stats::ar1_chain(b, 0.9999, n, c % 2 == 0 ? 5.0 : -5.0, false));
  }
  const double rhat_mixed = stats::split_rhat(mixed);
  const double rhat_unmixed = stats::split_rhat(unmixed);
  const double rn_mixed = stats::rank_normalized_split_rhat(mixed);
  const double rn_unmixed = stats::rank_normalized_split_rhat(unmixed);
  const double ess_mixed = stats::multichain_ess(mixed);
  const bool rhat_ok = rhat_mixed < 1.01 && rn_mixed < 1.01 && rhat_unmixed > 1.01 && rn_unmixed > 1.01;
  r.passed = r.passed && rhat_ok;
  r.statistic = worst;
  r.samples = static_cast<int64_t>(rhos.size()) * chains * n + 8 * n;
  r.message = msg + fmt::format("split R-hat mixed {:.4f} (rank-norm. {:.4f}), unmixed {:.3f} ({:.3f}){}; ESS {:.0f} "
                                "of {} (expected {:.0f})",
                                rhat_mixed, rn_mixed, rhat_unmixed, rn_unmixed, rhat_ok ? "" : " FAIL", ess_mixed,
                                4 * n, 4.0 * static_cast<double>(n) / stats::ar1_autocorrelation_time(0.9));
  r.details = {{"chains", chains},
               {"chain_length", n},
               {"tau", per_rho},
               {"split_rhat_mixed", rhat_mixed},
               {"split_rhat_unmixed", rhat_unmixed},
               {"rank_normalized_rhat_mixed", rn_mixed},
               {"rank_normalized_rhat_unmixed", rn_unmixed},
               {"multichain_ess_mixed", ess_mixed}};
  // Plot: estimated autocorrelation of one AR(0.9) chain against rho^k.
  const auto acf = stats::autocorrelation(mixed[0], 60);
  PlotSpec plot;
  plot.title = std::string("AR(1), rho = 0.9: autocorrelation");
  plot.x_label = std::string("lag k");
  plot.y_label = std::string("rho_k");
  PlotSeries est, exact;
  est.label = std::string("estimated");
  est.style = std::string("points");
  exact.label = std::string("0.9^k");
  exact.style = std::string("lines");
  for (size_t k = 0; k < acf.size(); ++k) {
    est.x.push_back(static_cast<double>(k));
    est.y.push_back(acf[k]);
    exact.x.push_back(static_cast<double>(k));
    exact.y.push_back(std::pow(0.9, static_cast<double>(k)));
  }
  plot.series = {est, exact};
  r.plots.push_back(plot);
  return r;
}

TB_REGISTER_CHECK({.name = "stats.mcmc.diagnostics",
                   .description = "Geyer's autocorrelation time matches (1 + rho) / (1 - rho) on AR(1) chains; split "
                                  "R-hat < 1.01 for mixed chains and > 1.01 for unmixed ones (negative control)",
                   .kind = CheckKind::kStatistical,
                   .run = run_mcmc_diagnostics});

}  // namespace
}  // namespace tb

// Convergence rates of the generic estimators (docs/validation.md F): RMSE against the sample budget N
// fitted with Ceres (validate/stats/convergence_fit.h) must have exponent 0.5 for MC, MIS, SMIS and
// MMIS on a smooth and a discontinuous integrand; the negative control, MMIS without its defensive
// technique (biased), must not.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analytic/classical_techniques_1d.h"
#include "analytic/fig1_setups.h"
#include "analytic/integrands.h"
#include "estimators/mc.h"
#include "estimators/mis.h"
#include "estimators/mmis_budget.h"
#include "estimators/smis.h"
#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "validate/registry.h"
#include "validate/stats/convergence_fit.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

// An estimator with a budget of N samples (N a power of two, at least 16).
using BudgetEstimator = std::function<double(const Integrand1D&, int64_t, Uniforms&)>;

const Fig1Bottom& bottom() {
  static const Fig1Bottom b = make_fig1_bottom();
  return b;
}

std::vector<std::pair<std::string, BudgetEstimator>> estimators() {
  static const std::vector<Classical1D> cs{Classical1D(UniformTechnique1D{0.0, 1.0}),
                                           Classical1D(TruncatedNormalTechnique1D(0.3, 0.1)),
                                           Classical1D(PiecewiseConstantTechnique1D({0.0, 0.5, 0.8, 1.0}, {1.0, 3.0, 0.5}))};
  return {
      {"mc_uniform", [](const Integrand1D& f, int64_t n, Uniforms& u) { return estimate_mc(f, cs[0], n, u).value; }},
      {"mis_balance", [](const Integrand1D& f, int64_t n, Uniforms& u) {
         const int counts[3] = {static_cast<int>(n / 2), static_cast<int>(n / 4), static_cast<int>(n / 4)};
         return estimate_mis(f, std::span<const Classical1D>(cs), std::span<const int>(counts), u).value;
       }},
      {"smis_defensive_n4", [](const Integrand1D& f, int64_t n, Uniforms& u) {
         double s = 0.0;
         for (int64_t k = 0; k < n / 4; ++k) s += estimate_smis(f, bottom().techniques[Fig1Bottom::kDefensive], 4, u).value;
         return s / static_cast<double>(n / 4);
       }},
      {"mmis_n2", [](const Integrand1D& f, int64_t n, Uniforms& u) {
         return estimate_mmis_budget(f, std::span<const ConditionalNormal1D>(bottom().techniques), 2, static_cast<int>(n), u)
             .value;
       }},
  };
}

stats::ConvergenceStudyOptions study_options(const CheckContext& ctx, uint64_t key, int64_t studies) {
  stats::ConvergenceStudyOptions o;
  o.log2_min = 4;
  o.log2_max = ctx.full ? 16 : 11;
  o.replicates = ctx.size(384, 64);
  if (ctx.full) o.replicates = static_cast<int64_t>(64 * ctx.sample_scale);
  o.seed = ctx.seed;
  o.key = key;
  // docs/validation.md F asks for a 99% interval; Šidák over the studies of this check keeps the family at 1%.
  o.fit.confidence = 1.0 - stats::sidak_alpha(0.01, studies);
  return o;
}

constexpr double kMaxHalfWidth = 0.03;  // docs/validation.md F

CheckResult run_convergence(const CheckContext& ctx) {
  const auto ests = estimators();
  const std::vector<std::string> problems{"smooth", "step"};
  const int64_t studies = static_cast<int64_t>(ests.size() * problems.size());
  CheckResult res;
  res.passed = true;
  res.statistic_name = "worst |alpha - 0.5|";
  res.alpha = 0.01;
  nlohmann::json rows = nlohmann::json::array();
  double worst = 0.0;
  int done = 0;
  for (const auto& pname : problems) {
    const Integrand1D& f = integrand_1d(pname);
    for (const auto& [ename, est] : ests) {
      const auto opts = study_options(ctx, hash_values(hash_string("mmis.convergence"), hash_string(ename + pname)), studies);
      const auto s = stats::run_convergence_study(
          [&f, est = est](int64_t n, uint64_t seed) {
            Rng r(seed);
            RngUniforms u(r);
            return est(f, n, u);
          },
          f.integral, opts);
      const bool ok = s.fit.converged && s.fit.alpha_lo <= 0.5 && 0.5 <= s.fit.alpha_hi &&
                      s.fit.half_width() <= kMaxHalfWidth && s.nonfinite == 0;
      worst = std::max(worst, std::abs(s.fit.alpha - 0.5));
      rows.push_back({{"estimator", ename}, {"problem", pname}, {"alpha", s.fit.alpha}, {"alpha_lo", s.fit.alpha_lo},
                      {"alpha_hi", s.fit.alpha_hi}, {"reduced_chi2", s.fit.reduced_chi2}, {"floor_b", s.floor_fit.b},
                      {"passed", ok}});
      if (!ok) {
        res.passed = false;
        res.message += fmt::format("{}/{}: alpha {:.3f} [{:.3f}, {:.3f}]; ", ename, pname, s.fit.alpha, s.fit.alpha_lo,
                                   s.fit.alpha_hi);
      }
      if (done == 0) res.plots.push_back(stats::convergence_plot(ename + " on " + pname, s.points, &s.fit, &s.floor_fit));
      for (const auto& p : s.points) res.samples += static_cast<int64_t>(p.n) * p.replicates;
      ctx.progress(static_cast<double>(++done) / static_cast<double>(studies));
    }
  }
  res.statistic = worst;
  res.details["studies"] = rows;
  res.details["max_half_width"] = kMaxHalfWidth;
  if (res.passed)
    res.message = fmt::format("{} estimator/problem pairs converge at rate 0.5 (interval contains 0.5, half-width <= {}); "
                              "worst |alpha - 0.5| = {:.3f}",
                              studies, kMaxHalfWidth, worst);
  return res;
}

TB_REGISTER_CHECK({.name = "mmis.convergence",
                   .description = "RMSE ~ N^-alpha fitted with Ceres: alpha = 0.5 (99% interval, Sidak over studies, "
                                  "half-width <= 0.03) for MC, MIS, SMIS, MMIS on a smooth and a step integrand",
                   .kind = CheckKind::kStatistical,
                   .run = run_convergence});

// Negative control: MMIS without the defensive technique misses two gaps of the support, so its
// RMSE levels off at the bias; the check's criterion must fail (exponent interval excluding 0.5 or
// wider than 0.03), or an error floor be detected.
CheckResult run_convergence_negative(const CheckContext& ctx) {
  const Fig1Bottom& b = bottom();
  static const std::vector<ConditionalNormal1D> partial(b.techniques.begin(), b.techniques.begin() + 3);
  const auto opts = study_options(ctx, hash_string("mmis.convergence.negative_control"), 1);
  const auto s = stats::run_convergence_study(
      [&](int64_t n, uint64_t seed) {
        Rng r(seed);
        RngUniforms u(r);
        // Budget n rounded down to a multiple of n·T = 6.
        return estimate_mmis_budget(*b.f, std::span<const ConditionalNormal1D>(partial), 2, static_cast<int>(n / 6 * 6), u)
            .value;
      },
      b.f->integral, opts);
  // The same pass criterion as mmis.convergence: 0.5 inside the interval and a half-width <= 0.03 (a
  // bent log-log curve inflates the rescaled interval, which the half-width bound catches).
  const bool rate_ok = s.fit.converged && s.fit.alpha_lo <= 0.5 && 0.5 <= s.fit.alpha_hi &&
                       s.fit.half_width() <= kMaxHalfWidth;
  CheckResult res;
  res.passed = !rate_ok || s.floor_fit.floor_detected();
  res.statistic_name = "alpha";
  res.statistic = s.fit.alpha;
  res.alpha = 0.01;
  for (const auto& p : s.points) res.samples += static_cast<int64_t>(p.n) * p.replicates;
  res.details = {{"alpha", s.fit.alpha}, {"alpha_lo", s.fit.alpha_lo}, {"alpha_hi", s.fit.alpha_hi},
                 {"floor_b", s.floor_fit.b}, {"floor_detected", s.floor_fit.floor_detected()}};
  res.plots.push_back(stats::convergence_plot("MMIS without defensive technique", s.points, &s.fit, &s.floor_fit));
  res.message = fmt::format("{} the biased MMIS: alpha {:.3f} [{:.3f}, {:.3f}], error floor b = {:.4g}{}",
                            res.passed ? "rejected" : "FAILED to reject", s.fit.alpha, s.fit.alpha_lo, s.fit.alpha_hi,
                            s.floor_fit.b, s.floor_fit.floor_detected() ? " (detected)" : "");
  return res;
}

TB_REGISTER_CHECK({.name = "mmis.convergence.negative_control",
                   .description = "The convergence fit must reject MMIS without its defensive technique (biased: error floor)",
                   .kind = CheckKind::kStatistical,
                   .run = run_convergence_negative});

}  // namespace
}  // namespace tb

// Unbiasedness of continuous MIS (estimators/cmis.h, West et al. 2020), registered like the SMIS and
// MMIS cases of mmis.unbiased (mmis_checks.cpp), with the same protocol:
//   cmis.unbiased                   CMIS with the continuous balance heuristic on every bounded 1D
//                                   catalogue integrand, two technique spaces whose marginals cover R
//   cmis.unbiased.negative_control  CMIS whose weights leave out the selection density p(t), so that
//                                   ∫_T w(t, x) dt = t_hi - t_lo ≠ 1: it must be rejected
// The techniques are UniformCentreNormal1D, whose marginal p(x) has a closed form (CMIS evaluates it
// at every sample; the quadrature marginal of ConditionalNormal1D would make 2^22 samples take hours).
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analytic/integrands.h"
#include "analytic/uniform_centre_normal_1d.h"
#include "estimators/cmis.h"
#include "lib/core/hash.h"
#include "validate/checks/estimator_check_helpers.h"
#include "validate/registry.h"

namespace tb {
namespace {

using checks::Realisation;

constexpr double kFamilyAlpha = 1e-5;  // as for mmis.unbiased, before the Šidák correction
constexpr int kBatches = 256;
constexpr int kSamplesPerRealisation = 8;

// t ~ U[0.02, 0.98], x | t ~ 0.8 N(t, 0.1²) + 0.2 U[0, 1]; and t ~ U[-0.1, 1.1], x | t ~ N(t, 0.15²).
const std::vector<UniformCentreNormal1D>& techniques() {
  static const std::vector<UniformCentreNormal1D> v{UniformCentreNormal1D(0.02, 0.98, 0.1, 0.2, "centre_defensive"),
                                                    UniformCentreNormal1D(-0.1, 1.1, 0.15, 0.0, "centre_wide")};
  return v;
}

CheckResult run_unbiased(const CheckContext& ctx) {
  // 2^22 (full) or 2^15 (quick) x-samples per technique-problem pair, 8 per realisation.
  const int64_t realisations = ctx.size(int64_t{1} << 12, int64_t{1} << 19);
  std::vector<checks::UnbiasedCase> cases;
  // Support condition: both marginals are positive on all of R. The singular integrand is left out
  // (finite variance needed by the t-test), as in mmis.unbiased.
  for (const auto& m : techniques())
    for (const auto& g : integrands_1d()) {
      if (g.singular) continue;
      cases.push_back({fmt::format("cmis_balance_n8_{}/{}", m.name(), g.name),
                       [&g, &m](Uniforms& u) { return estimate_cmis(g, m, kSamplesPerRealisation, u).value; }, g.integral});
    }
  return checks::unbiased_family(ctx, cases, hash_string("cmis.unbiased"), realisations, kBatches, kFamilyAlpha, kSamplesPerRealisation,
                                 "technique/problem", "Sidak over all technique-problem pairs");
}

TB_REGISTER_CHECK({.name = "cmis.unbiased",
                   .description = "Continuous MIS with the continuous balance heuristic (exact marginal) is unbiased on "
                                  "every bounded 1D catalogue integrand over two technique spaces: t-test of 256 batch "
                                  "means against the closed form, Sidak over pairs",
                   .kind = CheckKind::kStatistical,
                   .run = run_unbiased});

// The broken weight of the negative control: w(t, x) = p(x | t) / p(x), the balance heuristic with the
// selection density p(t) left out (the continuous analogue of forgetting c_i in one-sample MIS). Its
// integral over the technique space is ∫ p(x | t) dt / p(x) = (t_hi - t_lo) for t ~ U[t_lo, t_hi],
// so the estimate converges to (t_hi - t_lo) I instead of I.
struct WeightWithoutSelectionDensity {
  static constexpr int64_t pdf_evals = 1;
  double weight(const UniformCentreNormal1D& m, double x, const UniformCentreNormal1D::Aux& a, double q) const {
    return safe_ratio(q / m.aux_pdf(a), m.marginal_pdf(x));
  }
};
static_assert(ContinuousMisWeight<WeightWithoutSelectionDensity, UniformCentreNormal1D>);

CheckResult run_unbiased_negative(const CheckContext& ctx) {
  const int64_t realisations = ctx.size(int64_t{1} << 12, int64_t{1} << 19);
  const auto& m = techniques()[0];
  const auto& f = integrand_1d("fig1_three_peaks");
  const Realisation r = [&](Uniforms& u) {
    return estimate_cmis(f, m, kSamplesPerRealisation, u, WeightWithoutSelectionDensity{}).value;
  };
  const auto o = checks::test_unbiased("cmis_without_selection_density/fig1_three_peaks", r, f.integral, realisations,
                                       kBatches, ctx.seed, hash_string("cmis.unbiased.negative_control"), kFamilyAlpha);
  const double expected_bias = (m.t_hi() - m.t_lo() - 1.0) * f.integral;
  CheckResult res;
  res.passed = o.rejected;
  res.alpha = kFamilyAlpha;
  res.statistic_name = std::string(1, 't');  // not a literal: GCC 12 -Wrestrict false positive on it here
  res.statistic = o.t;
  res.p_value = o.p_value;
  res.samples = o.realisations * kSamplesPerRealisation;
  res.details = {{"mean", o.mean}, {"truth", o.truth}, {"expected_bias", expected_bias}, {"std_error", o.std_error},
                 {"min_detectable_bias", o.min_detectable_bias}};
  res.message = fmt::format(
      "{} the unnormalised weights: mean {:.6g} vs {:.6g} (expected bias {:.4g}, measured {:.4g}, t = {:.1f}, "
      "detectable at 90% power {:.2g})",
      o.rejected ? "rejected" : "FAILED to reject", o.mean, o.truth, expected_bias, o.mean - o.truth, o.t,
      o.min_detectable_bias);
  return res;
}

TB_REGISTER_CHECK({.name = "cmis.unbiased.negative_control",
                   .description = "CMIS with weights that leave out the selection density p(t) (they integrate to "
                                  "0.96, not 1, over the technique space) must be rejected by the unbiasedness t-test",
                   .kind = CheckKind::kStatistical,
                   .run = run_unbiased_negative});

}  // namespace
}  // namespace tb

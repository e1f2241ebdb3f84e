// Checks of the generic estimators on the analytic catalogue (docs/validation.md A, B, F):
//   mmis.unbiased                       every estimator on every problem where its support condition holds
//   mmis.unbiased.negative_control      MMIS without its defensive technique (a coverage gap) must be rejected
//   mmis.variance_vs_n                  MMIS_n variance non-increasing in n, approaching the exact reference MIS
//   mmis.variance_vs_n.negative_control an MMIS that does not marginalise must fail the same criteria
// The convergence-rate checks are in estimator_convergence_checks.cpp.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analytic/classical_techniques_1d.h"
#include "analytic/classical_techniques_2d.h"
#include "analytic/fig1_setups.h"
#include "analytic/integrands.h"
#include "analytic/mis_variance.h"
#include "analytic/quadrature.h"
#include "estimators/mc.h"
#include "estimators/mis.h"
#include "estimators/mmis.h"
#include "estimators/mmis_budget.h"
#include "estimators/smis.h"
#include "estimators/technique_subset.h"
#include "lib/core/hash.h"
#include "validate/checks/estimator_check_helpers.h"
#include "validate/registry.h"

namespace tb {
namespace {

using checks::Realisation;

// The classical set: its uniform member covers [0, 1], so every MIS variant is unbiased on every
// bounded integrand of the catalogue. Budget: 8 samples per realisation.
const std::vector<Classical1D>& classical_set() {
  static const std::vector<Classical1D> v{Classical1D(UniformTechnique1D{0.0, 1.0}),
                                          Classical1D(TruncatedNormalTechnique1D(0.3, 0.1)),
                                          Classical1D(PiecewiseConstantTechnique1D({0.0, 0.5, 0.8, 1.0}, {1.0, 3.0, 0.5}))};
  return v;
}
const std::vector<int> kClassicalCounts{4, 2, 2};
const std::vector<double> kOneSampleProbabilities{0.5, 0.25, 0.25};

const Fig1Bottom& bottom() {
  static const Fig1Bottom b = make_fig1_bottom();
  return b;
}
const Fig1Top& top() {
  static const Fig1Top t = make_fig1_top();
  return t;
}

struct NamedEstimator1D {
  std::string name;
  std::function<double(const Integrand1D&, Uniforms&)> run;
};

std::vector<NamedEstimator1D> estimators_1d() {
  std::vector<NamedEstimator1D> v;
  const auto cs = std::span<const Classical1D>(classical_set());
  const auto counts = std::span<const int>(kClassicalCounts);
  v.push_back({"mc_uniform", [](const Integrand1D& f, Uniforms& u) {
                 return estimate_mc(f, classical_set()[0], 8, u).value;
               }});
  v.push_back({"mc_piecewise", [](const Integrand1D& f, Uniforms& u) {
                 return estimate_mc(f, classical_set()[2], 8, u).value;
               }});
  v.push_back({"mis_balance", [=](const Integrand1D& f, Uniforms& u) {
                 return estimate_mis(f, cs, counts, u, BalanceHeuristic{}).value;
               }});
  v.push_back({"mis_power2", [=](const Integrand1D& f, Uniforms& u) {
                 return estimate_mis(f, cs, counts, u, PowerHeuristic{2.0}).value;
               }});
  v.push_back({"mis_maximum", [=](const Integrand1D& f, Uniforms& u) {
                 return estimate_mis(f, cs, counts, u, MaximumHeuristic{}).value;
               }});
  v.push_back({"mis_cutoff", [=](const Integrand1D& f, Uniforms& u) {
                 return estimate_mis(f, cs, counts, u, CutoffHeuristic{0.1}).value;
               }});
  for (auto [name, power] : {std::pair{"one_sample_balance", false}, std::pair{"one_sample_power2", true}}) {
    v.push_back({name, [=](const Integrand1D& f, Uniforms& u) {
                   const auto c = std::span<const double>(kOneSampleProbabilities);
                   double s = 0.0;
                   for (int k = 0; k < 8; ++k)
                     s += power ? estimate_one_sample_mis(f, cs, c, u, PowerHeuristic{2.0}).value
                                : estimate_one_sample_mis(f, cs, c, u, BalanceHeuristic{}).value;
                   return s / 8.0;
                 }});
  }
  v.push_back({"smis_defensive_n8", [](const Integrand1D& f, Uniforms& u) {
                 return estimate_smis(f, bottom().techniques[Fig1Bottom::kDefensive], 8, u).value;
               }});
  v.push_back({"mmis_fig1_bottom_n2", [](const Integrand1D& f, Uniforms& u) {
                 const std::vector<int> n(4, 2);
                 return estimate_mmis(f, std::span<const ConditionalNormal1D>(bottom().techniques),
                                      std::span<const int>(n), u).value;
               }});
  v.push_back({"mmis_fig1_top_mixed_split", [](const Integrand1D& f, Uniforms& u) {
                 const std::vector<int> nc{4}, nm{4};
                 return estimate_mmis(f, std::span<const Classical1D>(&top().classical, 1), std::span<const int>(nc),
                                      std::span<const ConditionalNormal1D>(&top().marginal, 1), std::span<const int>(nm), u)
                     .value;
               }});
  v.push_back({"mmis_fig1_bottom_random_subset", [](const Integrand1D& f, Uniforms& u) {
                 const std::vector<int> n(4, 2);
                 const bool always[4] = {false, false, false, true};
                 const auto sub = random_subset_counts(n, always, 1, u);
                 return estimate_mmis(f, std::span<const ConditionalNormal1D>(bottom().techniques),
                                      std::span<const int>(sub), u).value;
               }});
  return v;
}

constexpr double kFamilyAlpha = 1e-5;  // docs/validation.md A, before the Šidák correction below
constexpr int kBatches = 256;

CheckResult run_unbiased(const CheckContext& ctx) {
  // Samples: 2^22 (full) or 2^15 (quick) x-samples per estimator-problem pair; 8 per realisation.
  const int64_t realisations = ctx.size(int64_t{1} << 12, int64_t{1} << 19);
  std::vector<checks::UnbiasedCase> cases;
  // Support condition: every estimator below has a technique of positive density on all of [0, 1].
  // The singular integrand is left out: its support condition holds but the t-test needs finite
  // variance, which uniform-based techniques do not give for 1/sqrt(x).
  for (const auto& est : estimators_1d())
    for (const auto& g : integrands_1d()) {
      if (g.singular) continue;
      cases.push_back({est.name + "/" + g.name, [&g, run = est.run](Uniforms& u) { return run(g, u); }, g.integral});
    }
  const Product2D uniform2{}, peaked2{Classical1D(TruncatedNormalTechnique1D(0.4, 0.15)),
                                      Classical1D(MixtureTechnique1D({UniformTechnique1D{}, TruncatedNormalTechnique1D(0.4, 0.1)}, {0.3, 0.7}))};
  for (const auto& g : integrands_2d()) {
    if (g.singular) continue;
    cases.push_back({"mc_2d_product/" + g.name, [&g, peaked2](Uniforms& u) { return estimate_mc(g, peaked2, 8, u).value; },
                     g.integral});
    cases.push_back({"mis_2d_balance/" + g.name, [&g, uniform2, peaked2](Uniforms& u) {
                       const Product2D ts[2] = {uniform2, peaked2};
                       const int n[2] = {4, 4};
                       return estimate_mis(g, std::span<const Product2D>(ts), std::span<const int>(n), u).value;
                     },
                     g.integral});
  }
  return checks::unbiased_family(ctx, cases, hash_string("mmis.unbiased"), realisations, kBatches, kFamilyAlpha, 8,
                                 "estimator/problem", "Sidak over all estimator-problem pairs");
}

TB_REGISTER_CHECK({.name = "mmis.unbiased",
                   .description = "MC, multi- and one-sample MIS (balance, power, maximum, cutoff), SMIS and MMIS "
                                  "(mixed, random subset) are unbiased on every bounded 1D/2D catalogue integrand: "
                                  "t-test of 256 batch means against the closed form, Sidak over pairs",
                   .kind = CheckKind::kStatistical,
                   .run = run_unbiased});

// Negative control (docs/validation.md B): MMIS over the three partial techniques of Fig. 1 bottom, without
// the defensive one: the gaps (0.3, 0.38) and (0.62, 0.7) are sampled by no conditional technique,
// so the estimate misses ∫_gaps f. The check passes when the t-test rejects.
CheckResult run_unbiased_negative(const CheckContext& ctx) {
  const int64_t realisations = ctx.size(int64_t{1} << 12, int64_t{1} << 19);
  const auto& b = bottom();
  const std::vector<ConditionalNormal1D> partial(b.techniques.begin(), b.techniques.begin() + 3);
  const Realisation r = [&](Uniforms& u) {
    const std::vector<int> n(3, 2);
    return estimate_mmis(*b.f, std::span<const ConditionalNormal1D>(partial), std::span<const int>(n), u).value;
  };
  const auto o = checks::test_unbiased("mmis_without_defensive/fig1_three_peaks", r, b.f->integral, realisations,
                                       kBatches, ctx.seed, hash_string("mmis.unbiased.negative_control"), kFamilyAlpha);
  const double gap = integrate_1d(*b.f, 0.3, 0.38).value + integrate_1d(*b.f, 0.62, 0.7).value;
  CheckResult res;
  res.passed = o.rejected;
  res.alpha = kFamilyAlpha;
  res.statistic_name = "t";
  res.statistic = o.t;
  res.p_value = o.p_value;
  res.samples = o.realisations * 6;
  res.details = {{"mean", o.mean}, {"truth", o.truth}, {"expected_bias", -gap}, {"std_error", o.std_error}};
  res.message = fmt::format("{} the coverage gap: mean {:.6g} vs {:.6g} (expected bias {:.4g}, measured {:.4g}, t = {:.1f})",
                            o.rejected ? "rejected" : "FAILED to reject", o.mean, o.truth, -gap, o.mean - o.truth, o.t);
  return res;
}

TB_REGISTER_CHECK({.name = "mmis.unbiased.negative_control",
                   .description = "MMIS with the defensive technique removed (no conditional technique covers two gaps) "
                                  "must be rejected by the unbiasedness t-test",
                   .kind = CheckKind::kStatistical,
                   .run = run_unbiased_negative});

}  // namespace
}  // namespace tb

// MMIS variance against the number n of technique-sample pairs (docs/validation.md B; West et al. 2022,
// Sec. 3.2 and Fig. 1 bottom): at a fixed budget N = 64, MMIS_n (n pairs from each of T = 4
// techniques, N / (nT) realisations averaged) must have a variance non-increasing in n (within its
// standard error) that approaches the variance of the reference MIS with exact marginals, computed
// by quadrature; the quadrature value is itself cross-checked against replicates of the reference.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analytic/fig1_setups.h"
#include "estimators/mis.h"
#include "estimators/mmis_budget.h"
#include "lib/core/hash.h"
#include "validate/checks/estimator_check_helpers.h"
#include "validate/registry.h"

namespace tb {
namespace {

constexpr int kBudget = 64;
constexpr int kT = 4;
const int kNs[] = {1, 2, 4, 8, 16};
constexpr double kFamilyAlpha = 1e-5;

// A deliberately broken MMIS for the negative control: it does not marginalise over the sampled
// auxiliaries but weights every sample with n copies of the first conditional technique of each
// space, Σ_i n p_i(x | t_i1), so its extra variance cannot vanish as n grows.
double broken_mmis_budget(const Fig1Bottom& b, int n, Uniforms& u) {
  const int realisations = kBudget / (n * kT);
  double total = 0.0;
  for (int k = 0; k < realisations; ++k) {
    std::vector<ConditionalNormal1D::Aux> first;
    std::vector<double> xs;
    for (const auto& m : b.techniques)
      for (int j = 0; j < n; ++j) {
        const auto t = m.sample_aux(u);
        const auto x = m.sample(*t, u);
        if (j == 0) first.push_back(*t);
        xs.push_back(*x);
      }
    double s = 0.0;
    for (double x : xs) {
      double d = 0.0;
      for (size_t i = 0; i < b.techniques.size(); ++i) d += n * b.techniques[i].pdf(x, first[i]);
      s += safe_ratio((*b.f)(x), d);
    }
    total += s;
  }
  return total / realisations;
}

struct VarianceStudy {
  std::vector<stats::Welford> per_n;
  double reference = 0.0;
  bool passed = true;
  std::string message;
  nlohmann::json details;
  double min_p = 1.0;
};

VarianceStudy study(const CheckContext& ctx, bool broken, const std::string& key_name) {
  const auto b = make_fig1_bottom();
  const int64_t reps = ctx.size(2500, 100000);
  VarianceStudy s;
  s.reference = fig1_bottom_reference_variance(b, std::vector<int>(kT, kBudget / kT));
  for (size_t k = 0; k < std::size(kNs); ++k) {
    const int n = kNs[k];
    const checks::Realisation r = [&, n](Uniforms& u) {
      return broken ? broken_mmis_budget(b, n, u)
                    : estimate_mmis_budget(*b.f, std::span<const ConditionalNormal1D>(b.techniques), n, kBudget, u).value;
    };
    s.per_n.push_back(checks::replicate_moments(r, reps, ctx.seed, hash_values(hash_string(key_name), n)));
    ctx.progress(0.8 * static_cast<double>(k + 1) / std::size(kNs));
  }
  // Comparisons: 4 consecutive "no increase", 1 "decrease from n = 1 to n = 16", 1 reference z-test.
  const int64_t m = 6;
  const double alpha = stats::sidak_alpha(kFamilyAlpha, m);
  nlohmann::json rows = nlohmann::json::array();
  for (size_t k = 0; k < std::size(kNs); ++k)
    rows.push_back({{"n", kNs[k]}, {"variance", s.per_n[k].variance()}, {"se", s.per_n[k].variance_std_error()},
                    {"ratio_to_reference", s.per_n[k].variance() / s.reference}});
  s.details["per_n"] = rows;
  s.details["reference_variance_quadrature"] = s.reference;
  s.details["replicates"] = reps;
  s.details["alpha_per_comparison"] = alpha;
  for (size_t k = 0; k + 1 < std::size(kNs); ++k) {
    const auto& a = s.per_n[k];
    const auto& c = s.per_n[k + 1];
    const double se = std::hypot(a.variance_std_error(), c.variance_std_error());
    const auto z = stats::z_test_greater(c.variance() - a.variance(), se, 0.0);
    s.min_p = std::min(s.min_p, z.p_value);
    if (z.rejects(alpha)) {
      s.passed = false;
      s.message += fmt::format("variance increases from n = {} to n = {} (z = {:.2f}); ", kNs[k], kNs[k + 1], z.statistic);
    }
  }
  // The extra variance vanishes (West et al. 2022, Sec. 3.2): see checks::vanishing_excess.
  {
    const auto& a = s.per_n.front();
    const auto& c = s.per_n.back();
    const auto v = checks::vanishing_excess(a, c, s.reference, checks::kMmisApproachBand, alpha);
    s.details["decrease_z"] = v.fall_z;
    s.details["decrease_p"] = v.fall_p;
    s.details["ratio_n16"] = v.ratio_last;
    s.details["ratio_n16_se"] = v.ratio_last_se;
    s.details["approach_band"] = checks::kMmisApproachBand;
    s.details["equivalence_p"] = v.equivalence_p;
    if (!v.holds()) {
      s.passed = false;
      s.message += fmt::format("no significant approach to the reference (s²_1 = {:.4g}, s²_16 = {:.4g}, ref {:.4g}, fall z = "
                               "{:.2f}; ratio at n = 16 {:.3f} ± {:.3f}, band 1 ± {}); ",
                               a.variance(), c.variance(), s.reference, v.fall_z, v.ratio_last, v.ratio_last_se,
                               checks::kMmisApproachBand);
    }
  }
  // The quadrature reference against replicates of the reference MIS (exact marginals).
  {
    std::vector<ExactMarginal1D> exact;
    for (const auto& m : b.techniques) exact.push_back({&m});
    const std::vector<int> counts(kT, kBudget / kT);
    const checks::Realisation r = [&](Uniforms& u) {
      return estimate_mis(*b.f, std::span<const ExactMarginal1D>(exact), std::span<const int>(counts), u).value;
    };
    const auto w = checks::replicate_moments(r, ctx.size(120, 2000), ctx.seed, hash_values(hash_string(key_name), 999));
    const auto z = stats::z_test(w.variance(), w.variance_std_error(), s.reference);
    s.details["reference_variance_sampled"] = w.variance();
    s.details["reference_variance_sampled_se"] = w.variance_std_error();
    s.details["reference_z"] = z.statistic;
    s.min_p = std::min(s.min_p, z.p_value);
    if (z.rejects(alpha)) {
      s.passed = false;
      s.message += fmt::format("sampled reference variance {:.4g} ± {:.2g} disagrees with quadrature {:.4g}; ", w.variance(),
                               w.variance_std_error(), s.reference);
    }
  }
  ctx.progress(1.0);
  return s;
}

std::string summary(const VarianceStudy& s) {
  std::string r;
  for (size_t k = 0; k < std::size(kNs); ++k)
    r += fmt::format("{}{}:{:.3g}", k ? " " : "", kNs[k], s.per_n[k].variance() / s.reference);
  return r;
}

CheckResult run_variance(const CheckContext& ctx) {
  const auto s = study(ctx, false, "mmis.variance_vs_n");
  CheckResult res;
  res.passed = s.passed;
  res.alpha = stats::sidak_alpha(kFamilyAlpha, 6);
  res.statistic_name = "min p";
  res.statistic = s.min_p;
  res.p_value = s.min_p;
  res.samples = static_cast<int64_t>(s.per_n.size()) * s.per_n[0].count() * kBudget;
  res.details = s.details;
  res.message = s.passed ? fmt::format("Var(MMIS_n)/Var(reference MIS) for n = {}; reference {:.4g} (quadrature)", summary(s),
                                       s.reference)
                         : s.message;
  return res;
}

TB_REGISTER_CHECK({.name = "mmis.variance_vs_n",
                   .description = "MMIS_n variance (Fig. 1 bottom, N = 64, T = 4) is non-increasing in n and ends within 1 ± 0.25 of "
                                  "the exact reference MIS variance (quadrature, itself z-tested against replicates)",
                   .kind = CheckKind::kStatistical,
                   .run = run_variance});

CheckResult run_variance_negative(const CheckContext& ctx) {
  const auto s = study(ctx, true, "mmis.variance_vs_n.negative_control");
  CheckResult res;
  res.passed = !s.passed;
  res.alpha = stats::sidak_alpha(kFamilyAlpha, 6);
  res.statistic_name = "min p";
  res.statistic = s.min_p;
  res.p_value = s.min_p;
  res.samples = static_cast<int64_t>(s.per_n.size()) * s.per_n[0].count() * kBudget;
  res.details = s.details;
  res.message = (s.passed ? "FAILED to reject the non-marginalising MMIS: " : "rejected the non-marginalising MMIS: ") +
                (s.passed ? summary(s) : s.message);
  return res;
}

TB_REGISTER_CHECK({.name = "mmis.variance_vs_n.negative_control",
                   .description = "An MMIS that weights with n copies of one sampled conditional technique instead of "
                                  "marginalising must fail the variance-against-n criteria",
                   .kind = CheckKind::kStatistical,
                   .run = run_variance_negative});

}  // namespace
}  // namespace tb

// Multi-vertex filtering's MMIS denominator as a product of sums (West et al. 2022, Sec. 5, Eq. 14;
// estimators/mmis_filtering.h), on random cases: K = 2..4 filtered vertices, 1..6 prefixes per kernel,
// random positive tables p_k(x_k | y_{k,j}) (log-uniform over e^±4) for a few output samples of
// each case, all from fixed seeds (docs/validation.md). Deterministic checks, never rerun:
//   mmis.filtering.product_of_sums            Π_k S_k equals the explicit sum over every combination
//                                             (filtering_sum_of_products, and mmis.h's
//                                             for_each_mmis_weight over the Π_k m_k techniques), the
//                                             weights agree, Σ_k m_k evaluations; relative 1e-12
//   mmis.filtering.weights_sum_to_one         the MMIS weights of one output sample over all its
//                                             techniques (every combination, the classical one) sum to 1
//   mmis.filtering.linear_cost                pdf evaluations per output sample against K = 1..6:
//                                             fitted log-log slope 1 ± 0.1 (validate/stats/convergence_fit.h)
// Negative controls, each must be caught: a product of sums that drops one kernel's own prefix from
// its sum (the first two checks), and the explicit enumeration's cost (the slope check).
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "estimators/mmis.h"
#include "estimators/mmis_filtering.h"
#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "validate/registry.h"
#include "validate/stats/convergence_fit.h"

namespace tb {
namespace {

constexpr double kTol = 1e-12;

// One random case: the prefixes per kernel, and for a few of its output samples (each the sample of one
// combination j̄, its own technique) the table p_k(x_k | y_{k,j}) and the classical term Σ_c n_c p_c(x̄).
struct FilteringCase {
  std::vector<int> prefixes;
  int64_t techniques = 0;                          // Π_k m_k
  std::vector<int64_t> samples;                    // flat combination index (kernel 0 fastest) of each tabulated sample
  std::vector<std::vector<std::vector<double>>> pdf;  // pdf[s][k][j]
  std::vector<double> classical;                   // per tabulated sample; all 0 in the cases without one
  bool has_classical = false;
};

std::vector<int> decode(int64_t flat, std::span<const int> prefixes) {
  std::vector<int> j(prefixes.size());
  for (size_t k = 0; k < prefixes.size(); ++k) {
    j[k] = static_cast<int>(flat % prefixes[k]);
    flat /= prefixes[k];
  }
  return j;
}

double random_pdf(Rng& r) { return std::exp(8.0 * r.uniform() - 4.0); }

FilteringCase make_case(uint64_t seed, uint64_t key, uint64_t index, int kernels_lo, int kernels_hi, int max_samples) {
  Rng r = Rng::for_sample(seed, key, index);
  FilteringCase c;
  const int kernels = kernels_lo + static_cast<int>(r.uniform_below(static_cast<uint32_t>(kernels_hi - kernels_lo + 1)));
  for (int k = 0; k < kernels; ++k) c.prefixes.push_back(1 + static_cast<int>(r.uniform_below(6)));
  c.techniques = filtering_technique_count(c.prefixes);
  c.has_classical = r.uniform() < 0.5;
  const int64_t n = std::min<int64_t>(max_samples, c.techniques);
  for (int64_t s = 0; s < n; ++s) {
    // Every combination when there are at most max_samples of them, otherwise random ones (duplicates skipped).
    const int64_t flat = n == c.techniques ? s : static_cast<int64_t>(r.uniform_below(static_cast<uint32_t>(c.techniques)));
    bool dup = false;
    for (int64_t e : c.samples) dup |= e == flat;
    if (dup) continue;
    c.samples.push_back(flat);
    std::vector<std::vector<double>> table(c.prefixes.size());
    for (size_t k = 0; k < c.prefixes.size(); ++k)
      for (int j = 0; j < c.prefixes[k]; ++j) table[k].push_back(random_pdf(r));
    c.pdf.push_back(std::move(table));
    c.classical.push_back(c.has_classical ? random_pdf(r) : 0.0);
  }
  return c;
}

// The Π_k m_k combinations of one case as one marginal technique of mmis.h: Aux = the flat combination,
// Sample = the index of a tabulated output sample, p(x̄_s | t̄_j̄) = Π_k pdf[s][k][j_k] (Eq. 14, left side).
// Draws are built by the check, so the samplers are never called.
struct CombinationTechnique {
  using Sample = size_t;
  using Aux = int64_t;
  const FilteringCase* c = nullptr;
  std::optional<Aux> sample_aux(Uniforms&) const { return std::nullopt; }
  std::optional<Sample> sample(const Aux&, Uniforms&) const { return std::nullopt; }
  double pdf(Sample s, Aux flat) const {
    double p = 1.0;
    for (size_t k = 0; k < c->prefixes.size(); ++k) {
      p *= c->pdf[s][k][static_cast<size_t>(flat % c->prefixes[k])];
      flat /= c->prefixes[k];
    }
    return p;
  }
};
// The classical technique of the split denominator (Sec. 3.1), with n_c = 1: p_c(x̄_s) = classical[s].
struct TableClassical {
  using Sample = size_t;
  const FilteringCase* c = nullptr;
  std::optional<Sample> sample(Uniforms&) const { return std::nullopt; }
  double pdf(Sample s) const { return c->classical[s]; }
};
static_assert(MarginalTechnique<CombinationTechnique>);
static_assert(Technique<TableClassical>);

// The generic MMIS estimator's denominator and weight for every tabulated sample: one draw holding all
// Π_k m_k combinations as pairs (each n = 1); the samples not tabulated are marked failed, which keeps
// their techniques in every denominator (mmis.h) but skips their own evaluation.
std::vector<MmisWeight> generic_weights(const FilteringCase& c) {
  const CombinationTechnique tech{&c};
  const TableClassical cls{&c};
  const std::vector<int> nc{c.has_classical ? 1 : 0};
  MmisDraw<size_t, int64_t> d;
  if (c.has_classical) d.xs.push_back(std::nullopt);  // the classical sample itself is not tabulated
  std::vector<int64_t> sample_of(static_cast<size_t>(c.techniques), -1);
  for (size_t s = 0; s < c.samples.size(); ++s) sample_of[static_cast<size_t>(c.samples[s])] = static_cast<int64_t>(s);
  for (int64_t a = 0; a < c.techniques; ++a) {
    d.aux.push_back({0, a});
    d.xs.push_back(sample_of[static_cast<size_t>(a)] >= 0 ? std::optional<size_t>(static_cast<size_t>(sample_of[static_cast<size_t>(a)]))
                                                          : std::nullopt);
  }
  std::vector<MmisWeight> out(c.samples.size());
  for_each_mmis_weight(std::span<const TableClassical>(&cls, 1), std::span<const int>(nc),
                       std::span<const CombinationTechnique>(&tech, 1), d,
                       [&](size_t s, const MmisWeight& w) { out[s] = w; });
  return out;
}

auto table_pdf(const FilteringCase& c, size_t s) {
  return [&c, s](size_t k, int j) { return c.pdf[s][k][static_cast<size_t>(j)]; };
}

// The negative control's broken product of sums: at kernel `drop`, the sum leaves out the sample's own
// prefix (a filter that does not count the path's own prefix among the kernel's techniques).
double product_of_sums_without_own(const FilteringCase& c, size_t s, std::span<const int> own, size_t drop) {
  double product = 1.0;
  for (size_t k = 0; k < c.prefixes.size(); ++k) {
    double sum = 0.0;
    for (int j = 0; j < c.prefixes[k]; ++j)
      if (k != drop || j != own[k]) sum += c.pdf[s][k][static_cast<size_t>(j)];
    product *= sum;
  }
  return c.classical[s] + product;
}

double rel_err(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

int64_t quick_or_full(const CheckContext& ctx, int64_t quick, int64_t full) { return std::max<int64_t>(1, ctx.size(quick, full)); }

CheckResult run_product_of_sums(const CheckContext& ctx, bool control) {
  const uint64_t key = hash_string("mmis.filtering.product_of_sums");
  const int64_t cases = quick_or_full(ctx, 256, 4096);
  const int max_samples = ctx.full ? 48 : 16;
  double worst_vs_enum = 0.0, worst_vs_generic = 0.0, worst_weight = 0.0, smallest_control = INFINITY;
  int64_t samples = 0, bad_evals = 0, caught = 0, techniques = 0;
  std::string first;
  for (int64_t i = 0; i < cases; ++i) {
    const FilteringCase c = make_case(ctx.seed, key, static_cast<uint64_t>(i), 2, 4, max_samples);
    const auto generic = generic_weights(c);
    double case_control = INFINITY;
    const size_t drop = static_cast<size_t>(i) % c.prefixes.size();
    for (size_t s = 0; s < c.samples.size(); ++s) {
      const auto own = decode(c.samples[s], c.prefixes);
      const auto pdf = table_pdf(c, s);
      const FilteringWeight w = filtering_mmis_weight(std::span<const int>(c.prefixes), std::span<const int>(own), pdf, c.classical[s]);
      const double enumerated = c.classical[s] + filtering_sum_of_products(std::span<const int>(c.prefixes), pdf);
      const double den = control ? product_of_sums_without_own(c, s, own, drop) : w.denominator;
      const double e1 = rel_err(den, enumerated), e2 = rel_err(den, generic[s].denominator);
      const double e3 = std::abs(safe_ratio(w.own_pdf, den) - generic[s].weight);
      case_control = std::min(case_control, e1);
      if (std::max({e1, e2, e3}) > kTol && first.empty())
        first = fmt::format("case {} (m = [{}]), sample {}: D = {:.17g}, enumerated {:.17g}, generic {:.17g}", i,
                            fmt::join(c.prefixes, ","), c.samples[s], den, enumerated, generic[s].denominator);
      worst_vs_enum = std::max(worst_vs_enum, e1);
      worst_vs_generic = std::max(worst_vs_generic, e2);
      worst_weight = std::max(worst_weight, e3);
      int64_t sum_m = 0;
      for (int m : c.prefixes) sum_m += m;
      bad_evals += w.pdf_evals != sum_m;
      ++samples;
    }
    techniques += c.techniques;
    caught += case_control > kTol;
    smallest_control = std::min(smallest_control, case_control);
    ctx.progress(double(i + 1) / double(cases));
  }
  CheckResult r;
  r.samples = samples;
  r.statistic_name = control ? "min over cases of the relative error against the enumeration" : "max relative error";
  r.statistic = control ? smallest_control : std::max(worst_vs_enum, worst_vs_generic);
  r.details = {{"cases", cases},          {"output_samples", samples},           {"techniques", techniques},
               {"tolerance", kTol},       {"worst_vs_enumeration", worst_vs_enum}, {"worst_vs_for_each_mmis_weight", worst_vs_generic},
               {"worst_weight_abs", worst_weight}, {"pdf_eval_count_mismatches", bad_evals}};
  if (control) {
    r.details["cases_caught"] = caught;
    r.passed = caught == cases;
    r.message = fmt::format("negative control (one kernel's own prefix dropped from its sum, must be caught): {} in {} of "
                            "{} cases (smallest relative error {:.3g} > {:.0e})",
                            r.passed ? "caught" : "NOT caught", caught, cases, smallest_control, kTol);
  } else {
    r.passed = worst_vs_enum <= kTol && worst_vs_generic <= kTol && worst_weight <= kTol && bad_evals == 0 && samples > 0;
    r.message = fmt::format("{} cases, {} output samples: product of sums vs explicit enumeration max rel. {:.2g}, vs "
                            "for_each_mmis_weight {:.2g}, weights max abs {:.2g}; {} samples with pdf evaluations != "
                            "sum of m_k{}",
                            cases, samples, worst_vs_enum, worst_vs_generic, worst_weight, bad_evals,
                            first.empty() ? "" : "; first: " + first);
  }
  return r;
}

CheckResult run_weights_sum(const CheckContext& ctx, bool control) {
  const uint64_t key = hash_string("mmis.filtering.weights_sum_to_one");
  const int64_t cases = quick_or_full(ctx, 256, 4096);
  const int max_samples = ctx.full ? 48 : 16;
  double worst = 0.0, smallest_control = INFINITY;
  int64_t samples = 0, caught = 0;
  for (int64_t i = 0; i < cases; ++i) {
    const FilteringCase c = make_case(ctx.seed, key, static_cast<uint64_t>(i), 2, 4, max_samples);
    const size_t drop = static_cast<size_t>(i) % c.prefixes.size();
    double case_control = INFINITY;
    for (size_t s = 0; s < c.samples.size(); ++s) {
      const auto own = decode(c.samples[s], c.prefixes);
      const auto pdf = table_pdf(c, s);
      const FilteringWeight w = filtering_mmis_weight(std::span<const int>(c.prefixes), std::span<const int>(own), pdf, c.classical[s]);
      const double den = control ? product_of_sums_without_own(c, s, own, drop) : w.denominator;
      // Every technique of the sample: each combination j̄ (n = 1) and the classical one (Sec. 3.1).
      double sum = safe_ratio(c.classical[s], den);
      std::vector<int> j(c.prefixes.size(), 0);
      do {
        double p = 1.0;
        for (size_t k = 0; k < j.size(); ++k) p *= pdf(k, j[k]);
        sum += p / den;
      } while (next_filtering_combination(std::span<int>(j), std::span<const int>(c.prefixes)));
      worst = std::max(worst, std::abs(sum - 1.0));
      case_control = std::min(case_control, std::abs(sum - 1.0));
      ++samples;
    }
    caught += case_control > kTol;
    smallest_control = std::min(smallest_control, case_control);
    ctx.progress(double(i + 1) / double(cases));
  }
  CheckResult r;
  r.samples = samples;
  r.details = {{"cases", cases}, {"output_samples", samples}, {"tolerance", kTol}, {"worst_abs_sum_minus_one", worst}};
  if (control) {
    r.statistic_name = "min over cases of |sum of weights - 1|";
    r.statistic = smallest_control;
    r.details["cases_caught"] = caught;
    r.passed = caught == cases;
    r.message = fmt::format("negative control (weights normalised by a product of sums without one kernel's own prefix, must "
                            "be caught): {} in {} of {} cases (smallest |sum - 1| {:.3g})",
                            r.passed ? "caught" : "NOT caught", caught, cases, smallest_control);
  } else {
    r.statistic_name = "max |sum of weights - 1|";
    r.statistic = worst;
    r.passed = worst <= kTol && samples > 0;
    r.message = fmt::format("{} cases, {} output samples: max |sum of the MMIS weights over all techniques - 1| = {:.2g}",
                            cases, samples, worst);
  }
  return r;
}

// pdf evaluations per output sample against the number of filtered vertices K = 1..6 (m_k = 1..6 at random,
// the same cases for both forms): mean over cases, then the log-log slope from fit_power_law (which fits
// ln y = ln C - alpha ln K, so the slope is -alpha).
CheckResult run_linear_cost(const CheckContext& ctx, bool control) {
  const uint64_t key = hash_string("mmis.filtering.linear_cost");
  const int64_t cases = quick_or_full(ctx, 256, 2048);
  std::vector<stats::ConvergencePoint> points;
  nlohmann::json per_k = nlohmann::json::array();
  for (int kernels = 1; kernels <= 6; ++kernels) {
    int64_t evals = 0;
    for (int64_t i = 0; i < cases; ++i) {
      const FilteringCase c = make_case(ctx.seed, key, static_cast<uint64_t>(kernels * 1000003 + i), kernels, kernels, 1);
      const auto pdf = [&](size_t k, int j) {
        ++evals;
        return c.pdf[0][k][static_cast<size_t>(j)];
      };
      if (control) {
        (void)filtering_sum_of_products(std::span<const int>(c.prefixes), pdf);
      } else {
        (void)filtering_product_of_sums(std::span<const int>(c.prefixes), pdf);
      }
    }
    const double mean = static_cast<double>(evals) / static_cast<double>(cases);
    stats::ConvergencePoint p;
    p.n = kernels;
    p.rmse = mean;
    p.replicates = cases;
    points.push_back(p);
    per_k.push_back({{"kernels", kernels}, {"mean_pdf_evals", mean}});
    ctx.progress(kernels / 6.0);
  }
  const stats::PowerLawFit fit = stats::fit_power_law(points);
  const double slope = -fit.alpha;
  const bool linear = fit.converged && std::abs(slope - 1.0) <= 0.1;
  CheckResult r;
  r.statistic_name = "log-log slope of pdf evaluations against K";
  r.statistic = slope;
  r.samples = cases * 6;
  r.details = {{"per_kernel_count", per_k}, {"slope", slope}, {"slope_std_error", fit.alpha_std_error},
               {"tolerance", 0.1}, {"form", control ? "sum of products (explicit enumeration)" : "product of sums"}};
  if (control) {
    r.passed = fit.converged && !linear;
    r.message = fmt::format("negative control (the explicit enumeration, K·Π m_k evaluations, must be caught): {}, slope "
                            "{:.3f} (K = 1: {:.3g}, K = 6: {:.3g} evaluations)",
                            r.passed ? "caught" : "NOT caught", slope, points.front().rmse, points.back().rmse);
  } else {
    r.passed = linear;
    r.message = fmt::format("product of sums: slope {:.3f} ± {:.3f} of pdf evaluations against K = 1..6 (target 1 ± 0.1; "
                            "K = 1: {:.3g}, K = 6: {:.3g} evaluations)",
                            slope, fit.alpha_std_error, points.front().rmse, points.back().rmse);
  }
  return r;
}

TB_REGISTER_CHECK({.name = "mmis.filtering.product_of_sums",
                   .description = "multi-vertex filtering's Eq. 14 denominator as a product of per-kernel sums equals the "
                                  "explicit sum over every prefix combination and the generic MMIS denominator over "
                                  "them (relative 1e-12), with sum_k m_k pdf evaluations, on random 2-4 kernel cases",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_product_of_sums(c, false); }});
TB_REGISTER_CHECK({.name = "mmis.filtering.product_of_sums.negative_control",
                   .description = "a product of sums that drops one kernel's own prefix from its sum must differ from "
                                  "the explicit enumeration in every case",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_product_of_sums(c, true); }});
TB_REGISTER_CHECK({.name = "mmis.filtering.weights_sum_to_one",
                   .description = "the MMIS weights of one filtered output sample over all its techniques (every prefix "
                                  "combination and the classical one) sum to one (1e-12)",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_weights_sum(c, false); }});
TB_REGISTER_CHECK({.name = "mmis.filtering.weights_sum_to_one.negative_control",
                   .description = "weights normalised by a product of sums without one kernel's own prefix must not "
                                  "sum to one, in every case",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_weights_sum(c, true); }});
TB_REGISTER_CHECK({.name = "mmis.filtering.linear_cost",
                   .description = "pdf evaluations of the product of sums per output sample grow linearly with the "
                                  "number of filtered vertices: log-log slope 1 +- 0.1 over K = 1..6",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_linear_cost(c, false); }});
TB_REGISTER_CHECK({.name = "mmis.filtering.linear_cost.negative_control",
                   .description = "the explicit enumeration of Eq. 14 (K prod m_k evaluations) must fail the slope "
                                  "criterion of mmis.filtering.linear_cost",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_linear_cost(c, true); }});

}  // namespace
}  // namespace tb

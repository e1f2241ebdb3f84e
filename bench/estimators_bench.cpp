// MMIS_n estimates per second at the budget N = 64 with T = 4 marginal techniques (West et al. 2022,
// Fig. 1 bottom), n = 1..16, against the bare cost of the n·N·T conditional pdf evaluations it makes.
//   BM_MmisBudget/n      one estimate: N / (nT) realisations of Eq. 6, sampling included
//   BM_MmisEvaluate/n    Eq. 6 evaluated over pairs drawn beforehand (the estimator without sampling)
//   BM_MmisWeights/n     the per-sample MMIS weights alone (for_each_mmis_weight, what a renderer calls
//                        before splatting its RGB contribution) over the same pairs: no f
//   BM_BarePdfEvals/n    the same n·N·T evaluations of p(x | t) over pre-sampled (x, t), nothing else
//   BM_BareDraws         drawing the N pairs (t, x) into a preallocated array, nothing else (independent of n)
//   BM_BareIntegrand     the N evaluations of f at pre-sampled x, nothing else (independent of n)
// The estimate must do all three bare parts; what it costs beyond their sum is the estimator's overhead.
// Cost linear in n shows as a log-log slope of 1 of time against n (docs/estimators.md).
// The second argument is the cost of p(x | t): 0 = one exp() with the normaliser cached per pair
// (cheap: drawing the N pairs then dominates and is constant in n), 200 = a conditional pdf as
// costly as a path pdf (ConditionalNormal1D::Params::pdf_cost_repeats, the experiment's
// "expensive" case), where the n N T evaluations dominate as the paper's cost model assumes.
#include <vector>

#include <benchmark/benchmark.h>

#include "analytic/fig1_setups.h"
#include "estimators/mmis_budget.h"
#include "lib/core/rng.h"

namespace tb {
namespace {

constexpr int kBudget = 64;

void BM_MmisBudget(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom(static_cast<int>(state.range(1)));
  const int n = static_cast<int>(state.range(0));
  Rng rng(42);
  RngUniforms u(rng);
  int64_t evals = 0;
  for (auto _ : state) {
    const Estimate e = estimate_mmis_budget(*b.f, std::span<const ConditionalNormal1D>(b.techniques), n, kBudget, u);
    evals += e.pdf_evals;
    benchmark::DoNotOptimize(e.value);
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["pdf_evals/estimate"] = static_cast<double>(evals) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_MmisBudget)->ArgsProduct({{1, 2, 4, 8, 16}, {0, 20, 200}});

// The estimator's evaluation of Eq. 6 alone, over pairs drawn beforehand: what it adds to the
// bare pdf evaluations (denominator sums, f, the estimate's bookkeeping).
void BM_MmisEvaluate(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom(static_cast<int>(state.range(1)));
  const int n = static_cast<int>(state.range(0));
  const int realisations = kBudget / (n * static_cast<int>(b.techniques.size()));
  Rng rng(42);
  RngUniforms u(rng);
  const std::span<const ConditionalNormal1D> tech(b.techniques);
  const std::vector<int> counts(b.techniques.size(), n);
  using NC = NoClassical<double>;
  std::vector<MmisDraw<double, ConditionalNormal1D::Aux>> draws;
  for (int r = 0; r < realisations; ++r)
    draws.push_back(draw_mmis(std::span<const NC>{}, std::span<const int>{}, tech, std::span<const int>(counts), u));
  for (auto _ : state) {
    double s = 0.0;
    for (const auto& d : draws) s += evaluate_mmis(*b.f, std::span<const NC>{}, std::span<const int>{}, tech, d).value;
    benchmark::DoNotOptimize(s);
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_MmisEvaluate)->ArgsProduct({{1, 2, 4, 8, 16}, {0, 20, 200}});

// The per-sample weights (for_each_mmis_weight) over the pairs of BM_MmisEvaluate, without f: the Eq. 6
// denominators, the own densities and the weights, which is all the n·N·T pdf evaluations pay for.
void BM_MmisWeights(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom(static_cast<int>(state.range(1)));
  const int n = static_cast<int>(state.range(0));
  const int realisations = kBudget / (n * static_cast<int>(b.techniques.size()));
  Rng rng(42);
  RngUniforms u(rng);
  const std::span<const ConditionalNormal1D> tech(b.techniques);
  const std::vector<int> counts(b.techniques.size(), n);
  using NC = NoClassical<double>;
  std::vector<MmisDraw<double, ConditionalNormal1D::Aux>> draws;
  for (int r = 0; r < realisations; ++r)
    draws.push_back(draw_mmis(std::span<const NC>{}, std::span<const int>{}, tech, std::span<const int>(counts), u));
  for (auto _ : state) {
    double s = 0.0;
    for (const auto& d : draws)
      for_each_mmis_weight(std::span<const NC>{}, std::span<const int>{}, tech, d,
                           [&](double, const MmisWeight& w) { s += w.weight; });
    benchmark::DoNotOptimize(s);
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_MmisWeights)->ArgsProduct({{1, 2, 4, 8, 16}, {0, 20, 200}});

void BM_BarePdfEvals(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom(static_cast<int>(state.range(1)));
  const int n = static_cast<int>(state.range(0));
  const int t = static_cast<int>(b.techniques.size());
  const int realisations = kBudget / (n * t);
  Rng rng(42);
  RngUniforms u(rng);
  // The same draws as BM_MmisEvaluate (same seed): only the pdf evaluations are timed.
  std::vector<std::vector<std::pair<size_t, ConditionalNormal1D::Aux>>> aux(static_cast<size_t>(realisations));
  std::vector<std::vector<double>> xs(static_cast<size_t>(realisations));
  for (int r = 0; r < realisations; ++r)
    for (size_t i = 0; i < b.techniques.size(); ++i)
      for (int j = 0; j < n; ++j) {
        const auto a = b.techniques[i].sample_aux(u);
        aux[r].push_back({i, *a});
        xs[r].push_back(*b.techniques[i].sample(*a, u));
      }
  for (auto _ : state) {
    double s = 0.0;
    for (int r = 0; r < realisations; ++r)
      for (double x : xs[r])
        for (const auto& [i, a] : aux[r]) s += b.techniques[i].pdf(x, a);
    benchmark::DoNotOptimize(s);
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BarePdfEvals)->ArgsProduct({{1, 2, 4, 8, 16}, {0, 20, 200}});

// The N pair draws every MMIS_n estimate makes whatever n (sampling t, then x | t; the same order of
// uniforms as draw_mmis), into storage allocated once.
void BM_BareDraws(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom(static_cast<int>(state.range(0)));
  const size_t t = b.techniques.size();
  Rng rng(42);
  RngUniforms u(rng);
  std::vector<ConditionalNormal1D::Aux> aux(kBudget);
  std::vector<double> xs(kBudget);
  for (auto _ : state) {
    for (size_t j = 0; j < static_cast<size_t>(kBudget); ++j) {
      const auto& m = b.techniques[j % t];
      aux[j] = *m.sample_aux(u);
      xs[j] = *m.sample(aux[j], u);
    }
    benchmark::DoNotOptimize(xs.data());
    benchmark::ClobberMemory();
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BareDraws)->Arg(0)->Arg(20)->Arg(200);

// The N evaluations of f (fig1_three_peaks: three exp, called through Integrand1D) every estimate makes.
void BM_BareIntegrand(benchmark::State& state) {
  const Fig1Bottom b = make_fig1_bottom();
  Rng rng(42);
  std::vector<double> xs(kBudget);
  for (double& x : xs) x = rng.uniform();
  for (auto _ : state) {
    double s = 0.0;
    for (double x : xs) s += (*b.f)(x);
    benchmark::DoNotOptimize(s);
  }
  state.counters["estimates/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BareIntegrand);

}  // namespace
}  // namespace tb

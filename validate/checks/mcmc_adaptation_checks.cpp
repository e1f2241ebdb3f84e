// Regional adaptive Metropolis (Otsu et al., Sec. 4.4-5.3, Algorithm 1; estimators/mcmc/
// adaptation.h, partition.h, adaptive_chains.h) on the two-scale target of
// analytic/mcmc/regional_adaptive_walk.h: detailed balance of the regional kernel at frozen lambda,
// convergence of the per-region acceptance to a*, diminishing adaptation, stationarity of the
// frozen kernel, insensitivity to lambda0, each with a negative control that must be caught.
// Names: mcmc.adaptation.<what>; negative controls: mcmc.adaptation.negative_control.<defect>.<check>,
// passing when the broken variant IS rejected.
//
// Significance: statistical checks run at alpha = 1e-5 per check family, fixed seeds (the run
// seed; streams Rng::for_sample(seed, hash(check name), chain)). The tolerances of the
// deterministic-given-seed checks (acceptance within 0.02, lambda spread) are stated below.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "validate/mcmc/adaptation_runs.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/proposal_chi2.h"
#include "validate/mcmc/stationarity.h"
#include "validate/registry.h"

namespace tb {
namespace {

using namespace tb::mcmc;
constexpr double kAlpha = 1e-5;
constexpr double kAcceptanceTolerance = 0.02;  // |a_k - a*| over the last quarter of the adaptation
constexpr double kTailChangeBound = 0.1;       // max |d lambda| over the last 10% of updates
constexpr double kLambdaTolerance = 0.25;      // spread over lambda0 in {-10..5} of the tail-mean lambda_k

uint64_t key_of(const std::string& name) { return hash_string(name); }

CheckResult negate(CheckResult inner) {
  inner.passed = !inner.passed;
  inner.message = (inner.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + inner.message;
  return inner;
}

void add(const std::string& name, CheckKind kind, const std::string& desc, std::function<CheckResult(const CheckContext&)> f) {
  Registry::global().add(Check{.name = name, .description = desc, .kind = kind, .run = std::move(f)});
}

// The adaptation run of the checks: 16 chains, batches of one step each (16 observations per
// batch, about L = 10 per region: at most about one update per region at each frozen lambda; see
// docs/mcmc.md on why a long batch breaks the sign update); 30000 batches quick.
struct Sizes {
  int chains = 16, steps = 1, batches = 12000, measure_steps = 4000;
};
Sizes sizes(const CheckContext& ctx) {
  Sizes s;
  s.batches = static_cast<int>(ctx.size(30000, 200000));
  s.measure_steps = static_cast<int>(ctx.size(4000, 20000));
  return s;
}

// ---- detailed balance at frozen lambda, across region boundaries ---------------------------------
// Frozen scales sigma_0 = 0.25, sigma_1 = 4 (a factor 16); x uniform on [-3, 3], around the cut at 0,
// so that a large share of the proposals cross it.
template <class Wrap>
CheckResult run_pairwise(const CheckContext& ctx, const std::string& name, Wrap wrap) {
  const auto part = make_partition<1>("grid", two_scale_box());
  OtsuAdaptation ad(part->regions(), {});
  ad.set_lambda(0, std::log(0.25 * 0.25));
  ad.set_lambda(1, std::log(4.0 * 4.0));
  const auto kernel = wrap(regional_adaptive_kernel<1>(two_scale_1d(), part, &ad));
  const auto start = [](Uniforms& u) { return Point<1>{6.0 * u.next() - 3.0}; };
  const int64_t pairs = ctx.size(20000, 200000);
  const auto r = check_pairwise_balance<decltype(kernel)>(kernel, start, pairs, ctx.seed, key_of(name));
  // The same pairs again, to count those whose endpoints lie in different regions.
  int64_t crossing = 0;
  for (int64_t i = 0; i < pairs; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, key_of(name), static_cast<uint64_t>(i));
    RngUniforms u(rng);
    const Point<1> x = start(u);
    const auto m = kernel.sample_move(x, u);
    crossing += m && part->region_of(x) != part->region_of(m->y);
  }
  CheckResult res;
  res.passed = r.passed && 10 * crossing >= pairs;
  res.statistic_name = "max relative |F - B|";
  res.statistic = r.max_rel_residual;
  res.samples = r.pairs;
  res.message = r.message + fmt::format("; {} pairs cross the region boundary (at least 10% required)", crossing);
  res.details = {{"crossing_pairs", crossing}, {"violations", r.violations}, {"worst_index", r.worst_index},
                 {"tolerance", r.tolerance}};
  return res;
}

// ---- the regional walk samples its stated density, from a state of each region -------------------
// Frozen sigma = 0.25 / 4; x = -0.5 (region 0) and x = 2 (region 1), each at alpha / 2 (Sidak ~).
template <bool kMisstated>
CheckResult run_proposal_chi2(const CheckContext& ctx, const std::string& name) {
  const auto part = make_partition<1>("grid", two_scale_box());
  OtsuAdaptation ad(part->regions(), {});
  ad.set_lambda(0, std::log(0.25 * 0.25));
  ad.set_lambda(1, std::log(4.0 * 4.0));
  const RegionalAdaptiveWalk<1, RegionPartition<Point<1>>, OtsuAdaptation> correct(part, &ad);
  const auto walk = [&] {
    if constexpr (kMisstated)
      return MisstatedRegionalScale(correct);
    else
      return correct;
  }();
  const auto r0 = check_proposal_chi2_1d(walk, Point<1>{-0.5}, -1.75, 0.75, ctx.size(100000, 1000000), ctx.seed,
                                         key_of(name + ".0"));
  const auto r1 = check_proposal_chi2_1d(walk, Point<1>{2.0}, -18.0, 22.0, ctx.size(100000, 1000000), ctx.seed,
                                         key_of(name + ".1"));
  CheckResult res;
  res.alpha = kAlpha / 2;
  res.passed = r0.passed(kAlpha / 2) && r1.passed(kAlpha / 2);
  res.statistic_name = "min p over the two regions";
  res.p_value = std::min(r0.p_value(), r1.p_value());
  res.statistic = res.p_value;
  res.samples = r0.samples + r1.samples;
  res.message = "from x = -0.5 (sigma 0.25): " + r0.message() + "; from x = 2 (sigma 4): " + r1.message();
  res.details = {{"region0", r0.details()}, {"region1", r1.details()}};
  return res;
}

// ---- convergence of the per-region acceptance, and diminishing adaptation -------------------------
template <class Update>
CheckResult run_convergence(const CheckContext& ctx, const std::string& name) {
  const Sizes s = sizes(ctx);
  auto run = run_two_scale_adaptation<Update>("grid", {}, s.chains, s.batches, s.steps, ctx.seed, key_of(name));
  const auto acc = measure_two_scale_acceptance(run.partition, *run.adapter, run.states, s.measure_steps, ctx.seed,
                                                key_of(name + ".measure"));
  // For comparison: one global scale adapted the same way (reported, not decided).
  auto global = run_two_scale_adaptation<Update>("global", {}, s.chains, s.batches, s.steps, ctx.seed, key_of(name));
  const auto grid_part = make_partition<1>("grid", two_scale_box());
  const auto gk = regional_adaptive_kernel<1>(two_scale_1d(), global.partition, global.adapter.get());
  SynchronousAdaptiveChains gch(gk, *grid_part, *global.adapter, global.states, ctx.seed, key_of(name + ".global"));
  const auto gacc = gch.measure(s.measure_steps);
  CheckResult res;
  res.passed = true;
  res.statistic_name = "max |a_k - a*| over the last quarter of the adaptation";
  std::string msg;
  for (int k = 0; k < run.partition->regions(); ++k) {
    const double dev = std::abs(run.tail.mean(k) - 0.5);
    res.statistic = std::max(res.statistic, dev);
    res.passed = res.passed && dev <= kAcceptanceTolerance && run.tail.count[k] > 1000;
    msg += fmt::format("{}region {}: acceptance {:.4f} over the last quarter ({} proposals); final lambda {:.3f} "
                       "(sigma {:.3f}), acceptance there {:.4f} [one global scale, sigma {:.3f}: {:.4f}]",
                       k ? "; " : "", k, run.tail.mean(k), run.tail.count[k], run.adapter->lambda(k),
                       run.adapter->sigma(k), acc.mean(k), global.adapter->sigma(0), gacc.mean(k));
    res.details["lambda"].push_back(run.adapter->lambda(k));
    res.details["tail_acceptance"].push_back(run.tail.mean(k));
    res.details["frozen_acceptance"].push_back(acc.mean(k));
    res.details["global_acceptance"].push_back(gacc.mean(k));
  }
  res.samples = static_cast<int64_t>(s.chains) * (2 * s.batches * s.steps + 2 * s.measure_steps);
  res.message = msg + fmt::format(" (tolerance {})", kAcceptanceTolerance);
  return res;
}

template <class Update>
CheckResult run_diminishing(const CheckContext& ctx, const std::string& name) {
  const Sizes s = sizes(ctx);
  const AdaptationOptions o{};
  const auto run = run_two_scale_adaptation<Update>("grid", o, s.chains, s.batches, s.steps, ctx.seed, key_of(name));
  const auto d = check_diminishing(run.adapter->record(), run.partition->regions(), o.lambda0, 0.1, kTailChangeBound);
  CheckResult res;
  res.passed = d.passed;
  res.statistic_name = "max |d lambda| over the last 10% of updates";
  res.statistic = *std::max_element(d.tail_max_change.begin(), d.tail_max_change.end());
  res.samples = static_cast<int64_t>(s.chains) * s.batches * s.steps;
  res.message = d.message;
  res.details = {{"updates", d.updates}, {"first_gamma", d.first_gamma}, {"last_gamma", d.last_gamma},
                 {"tail_max_change", d.tail_max_change}};
  // gamma_j along the record of region 0, every 10th update: the visible decay.
  for (const auto& u : run.adapter->record())
    if (u.region == 0 && u.j % std::max(1, d.updates[0] / 10) == 0) res.details["gamma_trace_region0"].push_back(u.gamma);
  return res;
}

// ---- the frozen kernel after adaptation keeps pi ---------------------------------------------------
template <bool kRank>
CheckResult run_frozen_stationarity(const CheckContext& ctx, const std::string& name) {
  const Sizes s = sizes(ctx);
  const auto run = run_two_scale_adaptation<OtsuSignUpdate>("grid", {}, s.chains, s.batches, s.steps, ctx.seed,
                                                            key_of(name + ".adapt"));
  const auto target = two_scale_1d();
  const auto kernel = regional_adaptive_kernel<1>(target, run.partition, run.adapter.get());
  CheckResult res;
  res.alpha = kAlpha;
  std::string frozen = fmt::format(" (frozen lambda {:.3f}, {:.3f})", run.adapter->lambda(0), run.adapter->lambda(1));
  if constexpr (kRank) {
    const auto r = check_gandy_scott_rank(kernel, target, ctx.size(10000, 100000), 10, ctx.seed, key_of(name), kAlpha);
    res.passed = r.passed;
    res.statistic_name = "rank chi2";
    res.statistic = r.pearson.statistic;
    res.p_value = r.pearson.p_value;
    res.samples = r.replicates * r.length;
    res.message = r.message + frozen;
  } else {
    const auto r = check_stationarity_chi2(kernel, target, ctx.size(20000, 200000), 20, ctx.seed, key_of(name), kAlpha);
    res.passed = r.passed;
    res.statistic_name = "chi2";
    res.statistic = r.pearson.statistic;
    res.p_value = r.pearson.p_value;
    res.samples = r.chains * r.steps;
    res.message = r.message + frozen;
    res.details = {{"dof", r.pearson.dof}};
  }
  return res;
}

CheckResult run_keeps_adapting_check(const CheckContext& ctx, const std::string& name) {
  const int64_t chains = ctx.size(20000, 200000);
  const int steps = 20;
  const auto p = run_keeps_adapting(static_cast<int>(chains), steps, 1.0, ctx.seed, key_of(name));
  CheckResult res;
  res.passed = !p.rejects(kAlpha) && p.zero_expected_observed == 0;
  res.alpha = kAlpha;
  res.statistic_name = "chi2";
  res.statistic = p.statistic;
  res.p_value = p.p_value;
  res.samples = chains * steps;
  res.message = fmt::format("{} chains from exact draws adapting at every visit with constant gamma 1, {} steps: "
                            "chi2 = {:.1f} on {} dof, p = {:.3g} (alpha {:.2g})",
                            chains, steps, p.statistic, p.dof, p.p_value, kAlpha);
  return res;
}

// ---- insensitivity to the initial lambda -------------------------------------------------------------
CheckResult run_initial_lambda(const CheckContext& ctx, const std::string& name) {
  const Sizes s = sizes(ctx);
  const std::vector<double> lambda0 = {-10.0, -5.0, 0.0, 1.0, 5.0};
  std::vector<std::vector<double>> final(2), last(2);
  for (double l0 : lambda0) {
    const auto run = run_two_scale_adaptation<OtsuSignUpdate>("grid", {.lambda0 = l0}, s.chains, s.batches, s.steps,
                                                              ctx.seed, key_of(name));
    const auto tl = run.tail_lambda();
    for (int k = 0; k < 2; ++k) final[k].push_back(tl[k]), last[k].push_back(run.adapter->lambda(k));
  }
  CheckResult res;
  res.statistic_name = "max spread over lambda0 of lambda_k averaged over its last 10% of updates";
  std::string msg;
  for (int k = 0; k < 2; ++k) {
    const auto [lo, hi] = std::minmax_element(final[k].begin(), final[k].end());
    res.statistic = std::max(res.statistic, *hi - *lo);
    msg += fmt::format("{}region {}: lambda {:.3f}", k ? "; " : "", k, fmt::join(final[k], ", "));
    res.details["tail_mean_lambda"].push_back(final[k]);
    res.details["last_lambda"].push_back(last[k]);
  }
  res.passed = res.statistic <= kLambdaTolerance;
  res.samples = static_cast<int64_t>(lambda0.size()) * s.chains * s.batches * s.steps;
  res.message = msg + fmt::format(" for lambda0 = -10, -5, 0, 1, 5: spread {:.3f} (tolerance {})", res.statistic,
                                  kLambdaTolerance);
  return res;
}

const bool registered = [] {
  const auto identity = [](auto k) { return k; };
  const auto broken = [](auto k) { return ReverseRegionOfX(std::move(k)); };
  add("mcmc.adaptation.two_scale.grid.pairwise", CheckKind::kDeterministic,
      "Regional random walk at frozen lambda: pi(x) T(x->y) a = pi(y) T(y->x) a to 1e-9 on pairs crossing regions",
      [=](const CheckContext& c) { return run_pairwise(c, "mcmc.adaptation.two_scale.grid.pairwise", identity); });
  add("mcmc.adaptation.negative_control.reverse_region_of_x.pairwise", CheckKind::kDeterministic,
      "Negative control: the pairwise checker must reject T(y->x) evaluated with the scale of x's region",
      [=](const CheckContext& c) {
        return negate(run_pairwise(c, "mcmc.adaptation.negative_control.reverse_region_of_x.pairwise", broken));
      });
  add("mcmc.adaptation.two_scale.grid.proposal_chi2", CheckKind::kStatistical,
      "Regional random walk at frozen lambda samples its stated density from a state of each region (chi-square)",
      [](const CheckContext& c) { return run_proposal_chi2<false>(c, "mcmc.adaptation.two_scale.grid.proposal_chi2"); });
  add("mcmc.adaptation.negative_control.misstated_scale.proposal_chi2", CheckKind::kStatistical,
      "Negative control: the proposal chi-square must reject a regional walk stating a scale 5% off",
      [](const CheckContext& c) {
        return negate(run_proposal_chi2<true>(c, "mcmc.adaptation.negative_control.misstated_scale.proposal_chi2"));
      });
  add("mcmc.adaptation.two_scale.grid.convergence", CheckKind::kStatistical,
      "Otsu sign update (Eq. 5) on a 2-cell grid: per-region acceptance at frozen lambda within 0.02 of a* = 0.5",
      [](const CheckContext& c) { return run_convergence<OtsuSignUpdate>(c, "mcmc.adaptation.two_scale.grid.convergence"); });
  add("mcmc.adaptation.two_scale.grid_difference.convergence", CheckKind::kStatistical,
      "Robbins-Monro difference update on a 2-cell grid: per-region acceptance within 0.02 of a* = 0.5",
      [](const CheckContext& c) {
        return run_convergence<RobbinsMonroDifferenceUpdate>(c, "mcmc.adaptation.two_scale.grid_difference.convergence");
      });
  add("mcmc.adaptation.two_scale.grid.diminishing", CheckKind::kStatistical,
      "Diminishing adaptation: max |d lambda| over the last 10% of each region's updates <= 0.1",
      [](const CheckContext& c) { return run_diminishing<OtsuSignUpdate>(c, "mcmc.adaptation.two_scale.grid.diminishing"); });
  add("mcmc.adaptation.negative_control.constant_gamma.diminishing", CheckKind::kStatistical,
      "Negative control: the diminishing-adaptation check must reject gamma_j = gamma_max for every j",
      [](const CheckContext& c) {
        return negate(run_diminishing<ConstantGammaSignUpdate>(c, "mcmc.adaptation.negative_control.constant_gamma.diminishing"));
      });
  add("mcmc.adaptation.two_scale.grid.stationarity", CheckKind::kStatistical,
      "Kernel frozen after adaptation: chains from exact draws keep pi after 20 steps (chi-square, exact bin masses)",
      [](const CheckContext& c) { return run_frozen_stationarity<false>(c, "mcmc.adaptation.two_scale.grid.stationarity"); });
  add("mcmc.adaptation.two_scale.grid.rank", CheckKind::kStatistical,
      "Kernel frozen after adaptation: Gandy-Scott rank test",
      [](const CheckContext& c) { return run_frozen_stationarity<true>(c, "mcmc.adaptation.two_scale.grid.rank"); });
  add("mcmc.adaptation.negative_control.keeps_adapting.stationarity", CheckKind::kStatistical,
      "Negative control: chains adapting at every visit with a constant step must fail the stationarity chi-square",
      [](const CheckContext& c) {
        return negate(run_keeps_adapting_check(c, "mcmc.adaptation.negative_control.keeps_adapting.stationarity"));
      });
  add("mcmc.adaptation.two_scale.grid.initial_lambda", CheckKind::kStatistical,
      "lambda0 in {-10, -5, 0, 1, 5} end at the same per-region lambda within 0.25",
      [](const CheckContext& c) { return run_initial_lambda(c, "mcmc.adaptation.two_scale.grid.initial_lambda"); });
  return true;
}();

}  // namespace
}  // namespace tb

// The regional adaptation runs of the mcmc.adaptation.* checks and their negative controls, on the
// two-scale target of analytic/mcmc/regional_adaptive_walk.h. Broken variants are wrappers of the
// correct code (docs/mcmc.md, "Negative controls wrap the real thing"):
//  - ReverseRegionOfX: the regional kernel's Hastings terms with T(y -> x) evaluated with the scale
//    of x's region instead of y's (the proposal treated as symmetric across region boundaries);
//  - ConstantGammaSignUpdate: Eq. 5 with gamma_j = gamma_max for every j (no diminishing);
//  - within-chain adaptation that never stops (run_keeps_adapting): each chain owns its adapter,
//    updates it after every visit (L = 1) with a constant step, and moves with the current scale.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "analytic/mcmc/regional_adaptive_walk.h"
#include "estimators/mcmc/adaptation.h"
#include "estimators/mcmc/adaptive_chains.h"
#include "estimators/mcmc/kernel_step.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "validate/chi2/pearson_gof.h"

namespace tb::mcmc {

// Eq. 5 with a step that does not diminish (violates Roberts & Rosenthal 2009, Sec. 2, condition
// "diminishing adaptation").
struct ConstantGammaSignUpdate {
  static std::string name() { return "constant_gamma"; }
  static double gamma(const AdaptationOptions& o, int) { return o.gamma_max; }
  static double direction(double a_hat, double a_star) { return OtsuSignUpdate::direction(a_hat, a_star); }
};

// The regional kernel with the reverse density misstated: T(y -> x) computed with sigma(region(x)).
// K: the MetropolisHastings kernel of regional_adaptive_kernel<1> (single component, c = 1).
template <class K>
class ReverseRegionOfX {
 public:
  using State = typename K::State;
  using Move = typename K::Move;
  explicit ReverseRegionOfX(K k) : k_(std::move(k)) {}
  const auto& target() const { return k_.target(); }
  double target_density(const State& x) const { return k_.target_density(x); }
  std::optional<Move> sample_move(const State& x, Uniforms& u) const { return k_.sample_move(x, u); }
  const State& destination(const Move& m) const { return k_.destination(m); }
  Move reverse(const State& x, const Move& m) const { return k_.reverse(x, m); }
  double move_density(const State& x, const Move& m) const { return k_.move_density(x, m); }
  MoveTerms move_terms(const State& x, const Move& m) const {
    MoveTerms t = k_.move_terms(x, m);
    const auto& mut = k_.mixture().component(m.component);
    if (t.reverse > 0.0) t.reverse = WalkOf::density_with_scale(m.y, x, mut.scale(x));  // region of x
    return t;
  }
  double acceptance(const State& x, const Move& m) const { return decide(move_terms(x, m)).acceptance; }
  HastingsRatio rule() const { return {}; }

 private:
  using WalkOf = RegionalAdaptiveWalk<1, RegionPartition<Point<1>>, OtsuAdaptation>;
  K k_;
};

// The regional walk stating its density with a scale 5% larger than the regional one it samples
// with (a Proposal, for the proposal chi-square's negative control).
template <class Walk>
class MisstatedRegionalScale {
 public:
  using State = typename Walk::State;
  explicit MisstatedRegionalScale(const Walk& w) : w_(w) {}
  std::optional<State> propose(const State& x, Uniforms& u) const { return w_.propose(x, u); }
  double density(const State& x, const State& y) const { return Walk::density_with_scale(x, y, 1.05 * w_.scale(x)); }

 private:
  const Walk& w_;
};

// One adaptation run on the two-scale target: `chains` chains from exact draws, `batches`
// synchronous batches of `steps` transitions (adaptive_chains.h).
template <class Update>
struct AdaptationRun {
  std::shared_ptr<const RegionPartition<Point<1>>> partition;
  std::unique_ptr<RegionalAdaptation<Update>> adapter;
  std::vector<Point<1>> states;  // chain states at the end
  RegionAcceptance tail;         // acceptance of the proposals of the last quarter of the batches
  // Per region, the mean of lambda_k over the last 10% of its updates (the level lambda_k
  // fluctuates around under the sign update, whose steps are +-gamma_j).
  std::vector<double> tail_lambda() const {
    const int m = adapter->regions();
    std::vector<double> sum(m, 0.0);
    std::vector<int> n(m, 0);
    for (const auto& u : adapter->record())
      if (u.j > 0.9 * adapter->updates(u.region)) sum[u.region] += u.lambda, ++n[u.region];
    for (int k = 0; k < m; ++k) sum[k] = n[k] ? sum[k] / n[k] : adapter->lambda(k);
    return sum;
  }
};

// The same on any 1d target with exact draws (sample_exact), over the cells of two_scale_box().
template <class Update = OtsuSignUpdate, class Tg>
AdaptationRun<Update> run_regional_adaptation(const Tg& target, const std::string& partition, AdaptationOptions o,
                                              int chains, int batches, int steps, uint64_t seed, uint64_t key) {
  AdaptationRun<Update> run;
  run.partition = make_partition<1>(partition, two_scale_box());
  run.adapter = std::make_unique<RegionalAdaptation<Update>>(run.partition->regions(), o, true);
  const auto kernel = regional_adaptive_kernel<1>(target, run.partition, run.adapter.get());
  std::vector<Point<1>> starts(chains);
  for (int c = 0; c < chains; ++c) {
    Rng rng = Rng::for_sample(seed, key ^ 0x5747u, static_cast<uint64_t>(c));
    RngUniforms u(rng);
    starts[c] = target.sample_exact(u);
  }
  SynchronousAdaptiveChains ch(kernel, *run.partition, *run.adapter, std::move(starts), seed, key);
  run.tail = {std::vector<double>(run.partition->regions(), 0.0), std::vector<int64_t>(run.partition->regions(), 0)};
  for (int b = 0; b < batches; ++b) {
    const auto a = ch.run_batch(steps);
    if (4 * b < 3 * batches) continue;
    for (int k = 0; k < run.partition->regions(); ++k) run.tail.sum[k] += a.sum[k], run.tail.count[k] += a.count[k];
  }
  run.states = ch.states();
  return run;
}

template <class Update = OtsuSignUpdate>
AdaptationRun<Update> run_two_scale_adaptation(const std::string& partition, AdaptationOptions o, int chains,
                                               int batches, int steps, uint64_t seed, uint64_t key) {
  return run_regional_adaptation<Update>(two_scale_1d(), partition, o, chains, batches, steps, seed, key);
}

// Per-region acceptance at frozen lambda: `chains` chains continued from `starts`, `steps` each.
template <class Adapter>
RegionAcceptance measure_two_scale_acceptance(const std::shared_ptr<const RegionPartition<Point<1>>>& p,
                                              Adapter& ad, std::vector<Point<1>> starts, int steps, uint64_t seed,
                                              uint64_t key) {
  const auto kernel = regional_adaptive_kernel<1>(two_scale_1d(), p, &ad);
  SynchronousAdaptiveChains ch(kernel, *p, ad, std::move(starts), seed, key);
  return ch.measure(steps);
}

// The diminishing-adaptation check on a record: per region, the largest |lambda_j - lambda_{j-1}|
// over the final `tail` fraction of its updates must not exceed `bound`.
struct DiminishingResult {
  std::vector<double> tail_max_change, first_gamma, last_gamma;
  std::vector<int> updates;
  bool passed = false;
  std::string message;
};
inline DiminishingResult check_diminishing(const std::vector<AdaptationUpdateRecord>& rec, int regions,
                                           double lambda0, double tail, double bound) {
  DiminishingResult r;
  r.tail_max_change.assign(regions, 0.0);
  r.first_gamma.assign(regions, 0.0);
  r.last_gamma.assign(regions, 0.0);
  r.updates.assign(regions, 0);
  for (const auto& u : rec) r.updates[u.region] = std::max(r.updates[u.region], u.j);
  std::vector<double> prev(regions, lambda0);
  r.passed = true;
  for (const auto& u : rec) {
    if (u.j == 1) r.first_gamma[u.region] = u.gamma;
    r.last_gamma[u.region] = u.gamma;
    if (u.j > (1.0 - tail) * r.updates[u.region])
      r.tail_max_change[u.region] = std::max(r.tail_max_change[u.region], std::abs(u.lambda - prev[u.region]));
    prev[u.region] = u.lambda;
  }
  r.message = "";
  for (int k = 0; k < regions; ++k) {
    const bool ok = r.updates[k] >= 100 && r.tail_max_change[k] <= bound;
    r.passed = r.passed && ok;
    r.message += fmt::format("{}region {}: {} updates, gamma {:.3g} -> {:.3g}, max |d lambda| over the last {:.0f}% = "
                             "{:.3g} (bound {:.3g})",
                             k ? "; " : "", k, r.updates[k], r.first_gamma[k], r.last_gamma[k], 100 * tail,
                             r.tail_max_change[k], bound);
  }
  return r;
}

// Negative control: chains from exact draws that adapt within the chain at every visit with a
// constant step and move with their current scale; after `steps` transitions the final states are
// binned against the exact masses (Pearson, validate/chi2).
inline PearsonResult run_keeps_adapting(int chains, int steps, double gamma, uint64_t seed, uint64_t key) {
  const auto target = two_scale_1d();
  const auto part = make_partition<1>("grid", two_scale_box());
  std::vector<int> bin(chains);
  parallel_for(static_cast<size_t>(chains), [&](size_t c) {
    Rng rng = Rng::for_sample(seed, key, c);
    RngUniforms u(rng);
    RegionalAdaptation<ConstantGammaSignUpdate> ad(part->regions(), {.lambda0 = 0.0, .batch = 1, .gamma_max = gamma});
    ad.set_lambda(0, std::log(0.5 * 0.5));
    ad.set_lambda(1, std::log(4.0 * 4.0));
    const auto kernel = regional_adaptive_kernel<1>(target, part, &ad);
    Point<1> x = target.sample_exact(u);
    for (int s = 0; s < steps; ++s) {
      const int r = part->region_of(x);
      const auto t = step(kernel, x, u);
      ad.observe(r, t.acceptance);
      x = t.next();
    }
    bin[c] = target.bin_of(x);
  });
  std::vector<double> obs(target.bin_count(), 0.0), expct(target.bin_count());
  for (int b : bin) obs[b] += 1.0;
  for (int i = 0; i < target.bin_count(); ++i) expct[i] = target.bin_mass(i) * chains;
  return pearson_chi2_gof(obs, expct);
}

}  // namespace tb::mcmc

// `tb reproduce ramlt-target-acceptance`: the target acceptance a* of the adaptation (Otsu et al.,
// Sec. 8.1 and Sec. 9, "Target Acceptance Probability": a* = 0.234 "performs moderately worse than
// higher values of, e.g., 0.5 or 0.8"), a* in {0.234, 0.5, 0.8} (docs/ramlt.md, "Target
// acceptance"):
//  1. renders: RA-GRID (lens perturbation, N x N screen grid) on scenes/ramlt-glossy-diffuse.json
//     and glossy.json at equal mutations, rRMSE against ramlt-fig10's cached BDPT reference, the
//     perturbation's acceptance and the per-region acceptance it reached;
//  2. two analytic targets (analytic/mcmc/regional_adaptive_walk.h): the bimodal two-scale mixture
//     of the regional adaptation checks and the unimodal split normal; FIXED (lambda0 = 1 never
//     adapted), GLOBAL and the two-cell regional grid adapted at each a*, then frozen chains from
//     the adapted states, the multi-chain effective sample size of x (stats::multichain_ess, an
//     autocorrelation estimate) per transition and per wall second of the frozen phase.
// Passes when every figure is finite; the paper's claims are reported as observed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "validate/experiment.h"
#include "validate/experiments/ramlt_experiment_common.h"
#include "validate/mcmc/adaptation_runs.h"
#include "validate/stats/mcmc_diagnostics.h"

namespace tb {
namespace {

struct EssResult {
  double ess = 0.0, seconds = 0.0, acceptance = 0.0;
  std::vector<double> region_acceptance;  // per cell of the two-cell grid, frozen phase
  std::vector<double> lambda;
};

// Adapt with `partition` at a*, then run the frozen kernel `length` steps per chain from the
// adapted states, recording x.
template <class Tg>
EssResult analytic_ess(const Tg& target, const std::string& partition, double a_star, int chains, int batches,
                       int length, uint64_t seed, uint64_t key) {
  mcmc::AdaptationOptions o;
  o.target_acceptance = a_star;
  const auto run = mcmc::run_regional_adaptation(target, partition, o, chains, batches, 1, seed, key);
  const auto kernel = mcmc::regional_adaptive_kernel<1>(target, run.partition, run.adapter.get());
  const auto cells = mcmc::make_partition<1>("grid", mcmc::two_scale_box());
  std::vector<std::vector<double>> f(chains, std::vector<double>(length));
  std::vector<std::vector<double>> asum(chains, std::vector<double>(cells->regions(), 0.0));
  std::vector<std::vector<double>> acount(chains, std::vector<double>(cells->regions(), 0.0));
  const auto t0 = std::chrono::steady_clock::now();
  parallel_for(static_cast<size_t>(chains), [&](size_t c) {
    Rng rng = Rng::for_sample(seed, hash_values(key, hash_string("frozen")), c);
    RngUniforms u(rng);
    mcmc::Point<1> x = run.states[c];
    for (int t = 0; t < length; ++t) {
      const int r = cells->region_of(x);
      const auto tr = mcmc::step(kernel, x, u);
      asum[c][r] += tr.acceptance;
      acount[c][r] += 1.0;
      x = tr.next();
      f[c][t] = x[0];
    }
  });
  EssResult e;
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  e.ess = stats::multichain_ess(f);
  double s = 0.0, n = 0.0;
  for (int r = 0; r < cells->regions(); ++r) {
    double rs = 0.0, rn = 0.0;
    for (int c = 0; c < chains; ++c) rs += asum[c][r], rn += acount[c][r];
    e.region_acceptance.push_back(rn > 0 ? rs / rn : 0.0);
    s += rs, n += rn;
  }
  e.acceptance = s / n;
  for (int k = 0; k < run.adapter->regions(); ++k) e.lambda.push_back(run.adapter->lambda(k));
  return e;
}

ExperimentReport run(const ExperimentContext& ctx) {
  const int res = ctx.full ? 32 : 16;
  const int64_t chains = ctx.full ? 32 : 16;
  const int64_t ref_spp = ctx.full ? 16384 : 2048;
  const int reps = ctx.full ? 8 : 4;
  const int64_t mpp = ctx.full ? 4096 : 1024;
  const int grid = ctx.full ? 16 : 8;  // ramlt-fig10's N at the same size
  const std::vector<double> targets{0.234, 0.5, 0.8};
  const std::vector<std::string> scenes{"ramlt-glossy-diffuse.json", "glossy.json"};
  const int a_chains = 16, a_batches = ctx.full ? 100000 : 12000, a_length = ctx.full ? 100000 : 20000;
  const int a_reps = ctx.full ? 8 : 3;

  ExperimentReport rep;
  bool ok = true;
  nlohmann::json data = nlohmann::json::object();
  const size_t total = scenes.size() * targets.size() + 2 * 3 * targets.size();
  size_t done = 0;

  // 1. Renders.
  Table rt{.title = fmt::format("RA-GRID (lens, {0} x {0} grid) at equal mutations against a*", grid),
           .header = {"scene", "a*", "rRMSE", "replicate rRMSE (min / median / max)", "mutations/s", "perturbation acceptance",
                      "regions with >= 100 reports", "median region acceptance", "regions within 0.1 of a*"},
           .rows = {}};
  nlohmann::json rdata = nlohmann::json::array();
  for (const std::string& file : scenes) {
    const ramlt_exp::SceneSetup scene = ramlt_exp::load_scene_with_reference(file, res, ref_spp, ctx.seed);
    std::vector<double> e;
    for (const double a : targets) {
      path_space::RamltOptions o;
      o.perturbation = path_space::RamltPerturbation::kLens;
      o.partition = "grid";
      o.grid = grid;
      o.adaptation.target_acceptance = a;
      const ramlt_exp::Point p = ramlt_exp::measure(scene, o, chains, mpp, reps, [&](int rep_i) {
        return hash_values(ctx.seed, hash_string("ramlt-target-acceptance." + file), static_cast<int>(1000 * a), rep_i);
      });
      ok = ok && p.finite && std::isfinite(p.mutations_per_second());
      e.push_back(p.rrmse);
      const auto [lo, hi] = std::minmax_element(p.replicate_rrmse.begin(), p.replicate_rrmse.end());
      rt.rows.push_back({file, fmt::format("{:.3f}", a), fmt::format("{:.4f}", p.rrmse),
                         fmt::format("{:.4f} / {:.4f} / {:.4f}", *lo, p.median_rrmse(), *hi), fmt::format("{:.3g}", p.mutations_per_second()),
                         fmt::format("{:.3f}", p.acceptance), std::to_string(p.regions_reported),
                         fmt::format("{:.3f}", p.region_acceptance_median), fmt::format("{:.2f}", p.region_within_01)});
      rdata.push_back({{"scene", file}, {"a_star", a}, {"rrmse", p.rrmse}, {"replicate_rrmse", p.replicate_rrmse}, {"median_rrmse", p.median_rrmse()},
                       {"mutations_per_second", p.mutations_per_second()}, {"acceptance", p.acceptance},
                       {"regions_reported", p.regions_reported}, {"region_acceptance_median", p.region_acceptance_median},
                       {"region_within_01", p.region_within_01}});
      ctx.progress(static_cast<double>(++done) / static_cast<double>(total));
    }
    rep.claims.push_back(fmt::format(
        "{}: rRMSE at a* = 0.234 / 0.5 / 0.8: {:.4f} / {:.4f} / {:.4f}; 0.234 {} both higher values (Otsu Sec. 9: "
        "0.234 moderately worse than 0.5 or 0.8) [observed, not asserted]",
        file, e[0], e[1], e[2], e[0] > std::max(e[1], e[2]) ? "worse than" : "NOT worse than"));
  }
  rep.tables.push_back(std::move(rt));

  // 2. Analytic targets: the bimodal two-scale mixture and the unimodal split normal.
  nlohmann::json adata = nlohmann::json::array();
  const std::vector<std::pair<std::string, std::string>> variants{{"FIXED", "fixed"}, {"GLOBAL", "global"},
                                                                  {"REGIONAL (2-cell grid)", "grid"}};
  auto analytic = [&](const auto& target, const std::string& tname, const std::string& tdesc) {
    Table at{.title = fmt::format("{}: ESS of x after adaptation ({} chains x {} frozen steps, mean over {} replicates)",
                                  tdesc, a_chains, a_length, a_reps),
             .header = {"variant", "a*", "lambda (per region)", "acceptance (left / right cell)", "ESS",
                        "ESS per 1000 steps", "ESS / s", "ESS / s (min / max)"},
             .rows = {}};
    PlotSpec ep;
    ep.title = tdesc + ": ESS per second against a*";
    ep.x_label = "a*";
    ep.y_label = "ESS / s";
    ep.log_y = true;
    std::vector<std::vector<double>> ess_step(variants.size());
    for (size_t v = 0; v < variants.size(); ++v) {
      PlotSeries s;
      s.label = variants[v].first;
      for (const double a : targets) {
        double ess = 0.0, rate = 0.0, rmin = 1e300, rmax = 0.0;
        EssResult last;
        for (int r = 0; r < a_reps; ++r) {
          last = analytic_ess(target, variants[v].second, a, a_chains, a_batches, a_length, ctx.seed,
                              hash_values(hash_string("ramlt-target-acceptance." + tname + "." + variants[v].second),
                                          static_cast<int>(1000 * a), r));
          ok = ok && std::isfinite(last.ess) && last.ess > 0.0 && last.seconds > 0.0;
          ess += last.ess / a_reps;
          const double rr = last.ess / last.seconds;
          rate += rr / a_reps;
          rmin = std::min(rmin, rr), rmax = std::max(rmax, rr);
        }
        std::string lam;
        for (double l : last.lambda) lam += fmt::format("{}{:.2f}", lam.empty() ? "" : " / ", l);
        const double per_step = 1000.0 * ess / (a_chains * static_cast<double>(a_length));
        at.rows.push_back({variants[v].first, fmt::format("{:.3f}", a), lam,
                           fmt::format("{:.3f} / {:.3f}", last.region_acceptance[0], last.region_acceptance[1]),
                           fmt::format("{:.0f}", ess), fmt::format("{:.2f}", per_step), fmt::format("{:.3g}", rate),
                           fmt::format("{:.3g} / {:.3g}", rmin, rmax)});
        adata.push_back({{"target", tname}, {"variant", variants[v].first}, {"a_star", a}, {"lambda", last.lambda},
                         {"region_acceptance", last.region_acceptance}, {"ess", ess}, {"ess_per_1000_steps", per_step},
                         {"ess_per_second", rate}});
        ess_step[v].push_back(per_step);
        s.x.push_back(a);
        s.y.push_back(rate);
        ctx.progress(static_cast<double>(++done) / static_cast<double>(total));
      }
      ep.series.push_back(std::move(s));
    }
    for (size_t i = 0; i < targets.size(); ++i)
      rep.claims.push_back(fmt::format(
          "{}, a* = {:.3f}: ESS per 1000 steps FIXED {:.3g}, GLOBAL {:.3g}, REGIONAL {:.3g}: regional {} GLOBAL, "
          "GLOBAL {} FIXED [observed, not asserted]",
          tname, targets[i], ess_step[0][i], ess_step[1][i], ess_step[2][i],
          ess_step[2][i] > ess_step[1][i] ? "above" : "NOT above", ess_step[1][i] > ess_step[0][i] ? "above" : "NOT above"));
    rep.tables.push_back(std::move(at));
    rep.plots.push_back(std::move(ep));
  };
  analytic(mcmc::two_scale_1d(), "two-scale mixture", "Two-scale mixture 0.5 N(-2, 0.25^2) + 0.5 N(5, 2^2)");
  analytic(mcmc::SplitNormalTarget{}, "split normal",
           "Split normal exp(-x^2 / (2 s^2)), s = 0.25 (x < 0), 2 (x >= 0)");
  rep.passed = ok;
  rep.summary = fmt::format(
      "Target acceptance a* in {{0.234, 0.5, 0.8}} (Otsu Sec. 8.1, 9). Renders: RA-GRID, lens perturbation, {0} x {0} "
      "grid, on ramlt-glossy-diffuse and glossy, {1} x {1} images, {2} chains, {3} mutations per pixel (equal "
      "mutations), {4} replicates, rRMSE against the BDPT {5} spp reference of ramlt-fig10; per-region acceptance of "
      "the last replicate over regions with >= 100 reports. Analytic: the two-scale mixture of the mcmc.adaptation "
      "checks (bimodal: ESS of x counts mode crossings) and the unimodal split normal, cells cut at 0, {6} chains adapted over {7} synchronous batches of one step (Sec. 8.1 adaptation, lambda0 = 1), then {8} "
      "frozen steps per chain; ESS = multichain_ess of x (autocorrelation-based), per wall second of the "
      "frozen phase (2 threads on a shared machine: the time is load-dependent, ESS per step is not). Passes when "
      "every figure is finite; the claims list what was observed.",
      grid, res, chains, mpp, reps, ref_spp, a_chains, a_batches, a_length);
  data["renders"] = rdata;
  data["analytic"] = adata;
  data["config"] = {{"resolution", res}, {"chains", chains},   {"replicates", reps},     {"mutations_per_pixel", mpp},
                    {"grid", grid},      {"reference_spp", ref_spp}, {"analytic_chains", a_chains},
                    {"analytic_batches", a_batches}, {"analytic_length", a_length}, {"analytic_replicates", a_reps}};
  rep.data = data;
  return rep;
}

TB_REGISTER_EXPERIMENT({.name = "ramlt-target-acceptance",
                        .description = "Otsu et al. Sec. 9 a* study: rRMSE and reached acceptance of RA-GRID at a* = "
                                       "0.234, 0.5, 0.8; ESS/s of FIXED, GLOBAL, regional on the analytic two-scale target",
                        .run = run});

}  // namespace
}  // namespace tb

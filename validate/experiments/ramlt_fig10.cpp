// `tb reproduce ramlt-fig10`: the analogue of Otsu et al.'s Fig. 10 (rRMSE against render time,
// log-log, FIXED / GLOBAL / RA-GRID / RA-QUADTREE) on our scenes (docs/ramlt.md, "Fig. 10
// analogue"): the lens perturbation on scenes/ramlt-glossy-diffuse.json, glossy.json and
// ramlt-ajar-door.json, the multi-chain perturbation on caustic.json (RA-GRID = grid4d,
// RA-QUADTREE = quadtree4d there, Otsu Sec. 6.3). run_ramlt has no time budget (the chains are
// coupled), so the cost axis is a doubling mutation count with its measured wall time; 3 (full 8)
// replicates per point. rRMSE = sqrt(mean over pixels with reference luminance > 0 of ((L - L_ref)
// / L_ref)^2), luminance, against a BDPT reference of the same scene (its own noise is a floor,
// stated in the report). Fitted rates: ln rRMSE = ln C - alpha ln T (fit_time_power_law). The
// experiment passes when every run is finite and every fit converged; the paper's ordering claims
// are reported as observed, not asserted.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "validate/experiment.h"
#include "validate/experiments/ramlt_experiment_common.h"
#include "validate/stats/convergence_fit.h"

namespace tb {
namespace {

using path_space::RamltOptions;
using path_space::RamltPerturbation;

struct SceneCase {
  std::string file;
  RamltPerturbation perturbation;
};

ExperimentReport run(const ExperimentContext& ctx) {
  const int res = ctx.full ? 32 : 16;
  const int64_t chains = ctx.full ? 32 : 16;
  const int64_t ref_spp = ctx.full ? 16384 : 2048;
  const int grid = ctx.full ? 16 : 8;
  const int reps = ctx.full ? 8 : 3;
  const std::vector<int64_t> mpp = ctx.full ? std::vector<int64_t>{64, 128, 256, 512, 1024, 2048, 4096}
                                            : std::vector<int64_t>{64, 128, 256, 512, 1024};
  const std::vector<SceneCase> cases{{"ramlt-glossy-diffuse.json", RamltPerturbation::kLens},
                                     {"glossy.json", RamltPerturbation::kLens},
                                     {"ramlt-ajar-door.json", RamltPerturbation::kLens},
                                     {"caustic.json", RamltPerturbation::kMultiChain}};
  const std::vector<std::pair<std::string, std::string>> variants{
      {"FIXED", "fixed"}, {"GLOBAL", "global"}, {"RA-GRID", "grid"}, {"RA-QUADTREE", "quadtree"}};

  ExperimentReport rep;
  Table fits{.title = "Fitted rates ln rRMSE = ln C - alpha ln T (T = wall seconds), and rRMSE at the largest budget",
             .header = {"scene", "perturbation", "variant", "partition", "alpha", "99% interval", "rRMSE (largest)",
                        "seconds (largest)", "perturbation acceptance"},
             .rows = {}};
  nlohmann::json data = nlohmann::json::array();
  bool ok = true;
  const size_t total = cases.size() * variants.size() * mpp.size();
  size_t done = 0;
  for (const SceneCase& sc : cases) {
    const ramlt_exp::SceneSetup scene = ramlt_exp::load_scene_with_reference(sc.file, res, ref_spp, ctx.seed);
    const bool multi = sc.perturbation == RamltPerturbation::kMultiChain;
    const std::string pert = multi ? "multi-chain" : "lens";
    PlotSpec plot;
    plot.title = fmt::format("{} ({}, {} x {}): rRMSE against render time", sc.file, pert, res, res);
    plot.x_label = "wall seconds";
    plot.y_label = "rRMSE";
    plot.log_x = plot.log_y = true;
    double best = std::numeric_limits<double>::infinity();
    std::string best_name;
    std::vector<std::pair<std::string, double>> last;
    for (const auto& [label, part0] : variants) {
      std::string part = part0;
      if (multi && part == "grid") part = "grid4d";
      if (multi && part == "quadtree") part = "quadtree4d";
      PlotSeries s;
      s.label = label;
      std::vector<stats::ConvergencePoint> pts;
      double acc = 0.0;
      for (size_t i = 0; i < mpp.size(); ++i) {
        RamltOptions o;
        o.perturbation = sc.perturbation;
        o.partition = part;
        o.grid = grid;
        o.grid_bottom = grid;  // the same N for both levels, as Otsu Fig. 6
        const int64_t mutations = mpp[i] * res * res;
        o.refine_every = std::max<int64_t>(1, mutations / 8);  // about 8 refinements per run
        o.split_threshold = 200;
        const ramlt_exp::Point p = ramlt_exp::measure(scene, o, chains, mpp[i], reps, [&](int rep_i) {
          return hash_values(ctx.seed, hash_string("ramlt-fig10." + sc.file + "." + part), i, rep_i);
        });
        const double e = p.rrmse, t = p.seconds;
        ok = ok && p.finite;
        acc = p.acceptance;
        s.x.push_back(t);
        s.y.push_back(e);
        stats::ConvergencePoint cp;
        cp.n = static_cast<double>(mutations);
        cp.rmse = e;
        cp.replicates = reps;
        cp.seconds = t;
        pts.push_back(cp);
        data.push_back({{"scene", sc.file}, {"perturbation", pert}, {"variant", label}, {"partition", part},
                        {"mutations", mutations}, {"seconds", t}, {"rrmse", e}, {"regions", p.regions},
                        {"regions2", p.regions2}, {"acceptance", acc}});
        ctx.progress(static_cast<double>(++done) / static_cast<double>(total));
      }
      const stats::PowerLawFit f = stats::fit_time_power_law(pts);
      ok = ok && f.converged;
      fits.rows.push_back({sc.file, pert, label, part, fmt::format("{:.3f}", f.alpha),
                           fmt::format("[{:.3f}, {:.3f}]", f.alpha_lo, f.alpha_hi), fmt::format("{:.4f}", s.y.back()),
                           fmt::format("{:.2f}", s.x.back()), fmt::format("{:.3f}", acc)});
      last.push_back({label, s.y.back()});
      if (s.y.back() < best) {
        best = s.y.back();
        best_name = label;
      }
      plot.series.push_back(std::move(s));
    }
    rep.plots.push_back(std::move(plot));
    const double fixed = last[0].second, global = last[1].second;
    const double ra = std::min(last[2].second, last[3].second);
    rep.claims.push_back(fmt::format(
        "{} ({}): lowest rRMSE at the largest budget: {} ({:.4f}); regional (best of RA-GRID / RA-QUADTREE {:.4f}) "
        "{} GLOBAL ({:.4f}); GLOBAL {} FIXED ({:.4f}) [observed, not asserted]",
        sc.file, pert, best_name, best, ra, ra < global ? "below" : "NOT below", global,
        global < fixed ? "below" : "NOT below", fixed));
  }
  rep.tables.push_back(std::move(fits));
  rep.passed = ok;
  rep.summary = fmt::format(
      "Otsu et al. Fig. 10 analogue: rRMSE against wall time for FIXED (lambda = 1), GLOBAL, RA-GRID and RA-QUADTREE, "
      "lens perturbation on ramlt-glossy-diffuse, glossy and ramlt-ajar-door, multi-chain perturbation on caustic "
      "(RA-GRID = grid4d, RA-QUADTREE = quadtree4d). {} x {} images, {} chains, {} to {} mutations per pixel "
      "(doubling; {} replicates per point, rRMSE their root mean square), grid N_top = N_bottom = {}, quadtree refined every 1/8 of the run above "
      "200 reports (Otsu's M_split = 5000, M_refine = 10^7 suit 10-minute renders, not these). Reference: BDPT "
      "{} spp (cached on disk, reports/cache), whose own noise is a floor under every rRMSE. Passes when every run is finite and every fit converged; "
      "the claims list what was observed.",
      res, res, chains, mpp.front(), mpp.back(), reps, grid, ref_spp);
  rep.data = {{"runs", data},       {"resolution", res}, {"chains", chains},
              {"replicates", reps}, {"reference_spp", ref_spp}, {"grid", grid}};
  return rep;
}

TB_REGISTER_EXPERIMENT({.name = "ramlt-fig10",
                        .description = "Otsu et al. Fig. 10 analogue: rRMSE against render time of FIXED, GLOBAL, "
                                       "RA-GRID, RA-QUADTREE for the lens and multi-chain perturbations",
                        .run = run});

}  // namespace
}  // namespace tb

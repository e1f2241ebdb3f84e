#include "app/compare_scene.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "app/compare_metrics.h"
#include "app/mpi_world.h"
#include "app/progress.h"
#include "app/scene_loading.h"
#include "lib/core/atomic_file.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/film/exr_io.h"
#include "lib/film/film.h"
#include "lib/film/png_preview.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/registry/integrator_registry.h"
#include "reports/compare_report.h"
#include "validate/experiment.h"
#include "validate/plot_spec.h"
#include "validate/stats/convergence_fit.h"

namespace tb {

namespace {

namespace fs = std::filesystem;

// JSON has no NaN / Inf: written as strings so nothing is lost silently.
nlohmann::json num(double v) {
  if (std::isfinite(v)) return v;
  if (std::isnan(v)) return "NaN";
  return v > 0 ? "Inf" : "-Inf";
}

// The reference integrator and its budget factor when no --reference is given.
constexpr const char* kReferenceIntegrator = "bdpt";
constexpr double kReferenceBudgetFactor = 4.0;
// Passes of a time-budgeted run: far more than any budget reaches, so the budget ends the run.
// With spp = n * passes every pass is n samples per pixel (path tracing, light tracing, BDPT),
// n P mutations after a bootstrap (PSSMLT, MMLT: lib/mcmc/pss/pss_driver.cpp) or one chain of
// n P mutations (path-space MLT: lib/mcmc/path_space/mlt.cpp), P = pixel count.
constexpr int64_t kOpenEndedPasses = int64_t(1) << 24;

struct Run {
  double budget = 0.0, seconds = 0.0;
  int64_t passes = 0, nonfinite_samples = 0;
  RunReport report;
  std::vector<Rgb> image;  // the mean image
  std::string exr;
  bool resumed = false;
};

nlohmann::json mutations_json(const RunReport& r) {
  nlohmann::json m = nlohmann::json::array();
  for (const auto& x : r.mutations)
    m.push_back({{"name", x.name}, {"proposed", x.proposed}, {"accepted", x.accepted}, {"acceptance", x.acceptance()}});
  return m;
}

RunReport mutations_from_json(const nlohmann::json& rec) {
  RunReport r;
  for (const auto& m : rec.value("mutations", nlohmann::json::array()))
    r.mutations.push_back({m.value("name", ""), m.value("proposed", int64_t{0}), m.value("accepted", int64_t{0})});
  r.mutations_total = rec.value("mutations_total", int64_t{0});
  r.mutations_per_second = rec.value("mutations_per_second", 0.0);
  return r;
}

// One time-budgeted render to STEM.exr + STEM.json, or its reload with --resume when STEM.json
// holds the same key. Empty when interrupted during the render (a partial run is not its budget).
std::optional<Run> render_run(const World& world, const IntegratorInfo& info, const RenderSettings& base,
                              const std::string& stem, const nlohmann::json& key, bool resume, ProgressLine& line,
                              const std::string& label, const std::atomic<bool>* interrupted) {
  const std::string exr = stem + ".exr", rec_path = stem + ".json";
  Run run;
  run.budget = base.time_budget_s;
  run.exr = exr;
  if (resume && fs::exists(rec_path) && fs::exists(exr)) {
    const nlohmann::json rec = nlohmann::json::parse(read_file(rec_path));
    if (rec.value("key", nlohmann::json()) == key) {
      run.seconds = rec.value("seconds", 0.0);
      run.passes = rec.value("passes", int64_t{0});
      run.nonfinite_samples = rec.value("nonfinite_samples", int64_t{0});
      run.report = mutations_from_json(rec);
      run.image = read_exr(exr).rgb;
      run.resumed = true;
      return run;
    }
  }
  RenderSettings st = base;
  st.report = &run.report;
  line.start(label);
  const auto t0 = std::chrono::steady_clock::now();
  st.progress = [&](double) {
    line.update(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / st.time_budget_s);
  };
  Film film(world.camera().width(), world.camera().height());
  run.passes = info.render(world, st, film);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  line.finish();
  if (interrupted && interrupted->load()) return std::nullopt;
  run.nonfinite_samples = film.nonfinite().count();
  run.image = film.mean_image();
  write_exr(exr, exr_image_from_welch(film.welch()));
  nlohmann::json rec = {{"key", key},
                        {"seconds", run.seconds},
                        {"passes", run.passes},
                        {"nonfinite_samples", run.nonfinite_samples}};
  if (!run.report.mutations.empty()) {
    rec["mutations"] = mutations_json(run.report);
    rec["mutations_total"] = run.report.mutations_total;
    rec["mutations_per_second"] = run.report.mutations_per_second;
  }
  write_file_atomic(rec_path, rec.dump(1));
  return run;
}

std::string acceptance_text(const RunReport& r) {
  std::string s;
  for (const auto& m : r.mutations) s += fmt::format("{}{} {:.3f}", s.empty() ? "" : ", ", m.name, m.acceptance());
  return s.empty() ? "-" : s;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

struct IntegratorResult {
  std::string name;
  std::string error;  // the integrator threw (e.g. path-space MLT on a thin-lens camera)
  std::vector<Run> runs;
  std::vector<compare::RelativeError> errors;
  std::optional<stats::PowerLawFit> fit;
  std::string fit_error;
};

}  // namespace

int cmd_compare_scene(const CompareSceneArgs& a, const std::atomic<bool>* interrupted) {
  // Settings are strict: every problem is named before anything renders.
  if (a.integrators.empty()) {
    fmt::print(stderr, "tb compare: --integrators needs at least one name (see tb render --list)\n");
    return 2;
  }
  std::vector<const IntegratorInfo*> infos;
  for (const auto& n : a.integrators) {
    const IntegratorInfo* i = find_integrator(n);
    if (!i) {
      std::vector<std::string> names;
      for (const auto& x : integrators()) names.push_back(x.name);
      fmt::print(stderr, "tb compare: unknown integrator '{}' (known: {})\n", n, join(names, ", "));
      return 2;
    }
    for (const IntegratorInfo* j : infos)
      if (j == i) {
        fmt::print(stderr, "tb compare: integrator '{}' given twice\n", n);
        return 2;
      }
    infos.push_back(i);
  }
  if (!(a.time_s > 0) || !std::isfinite(a.time_s)) {
    fmt::print(stderr, "tb compare: --time S (seconds, > 0) is required with a scene\n");
    return 2;
  }
  if (!a.reference.empty() && !fs::exists(a.reference)) {
    fmt::print(stderr, "tb compare: reference '{}' does not exist\n", a.reference);
    return 2;
  }

  // Under mpirun a rank that cannot load the scene (a file missing on its machine) still takes part
  // in the one gather below, with its message and no files: rank 0 then renders that rank's items
  // itself (or, when rank 0 is the one that failed, names it and the run fails), instead of every
  // other rank waiting for it forever.
  std::unique_ptr<World> world;
  try {
    world = load_scene_file(a.scene, a.resolution);
  } catch (const std::exception& e) {
    if (mpi::world().size == 1) throw;
    const std::vector<uint8_t> packed = nlohmann::json::to_cbor(
        nlohmann::json{{"files", nlohmann::json::array()}, {"done", 0}, {"lost", 0}, {"error", e.what()}});
    mpi::gather(std::string(packed.begin(), packed.end()));
    // Only rank 0's exit status may be non-zero: mpirun ends the whole job at the first non-zero one.
    if (mpi::world().rank != 0) return 0;
    fmt::print(stderr, "tb compare under mpirun: rank 0 of {} failed: {}\n", mpi::world().size, e.what());
    return 1;
  }
  const int W = world->camera().width(), H = world->camera().height();
  const int max_depth = world->integrator_defaults().value("max_depth", 10);
  const std::string stem = fs::path(a.scene).stem().string();
  const std::string out = a.out.empty() ? "reports/out/compare-" + stem : a.out;
  fs::create_directories(fs::path(out) / "runs");
  fs::create_directories(fs::path(out) / "images");
  const std::vector<double> budgets = compare::checkpoint_budgets(a.time_s, a.checkpoints);
  ThreadLimit limit(static_cast<size_t>(std::max(0, a.threads)));
  ProgressLine line(!a.no_progress && isatty(STDERR_FILENO));
  const unsigned hw = std::thread::hardware_concurrency();

  RenderSettings base;
  base.spp = base.passes = kOpenEndedPasses;
  base.max_depth = max_depth;
  base.interrupted = interrupted;
  const int64_t P = int64_t(W) * int64_t(H);
  auto pass_spp = [&](const std::string& integ) { return a.pass_spp > 0 ? a.pass_spp : default_pass_spp(integ, P); };
  auto settings_for = [&](const std::string& integ, double budget, uint64_t seed) {
    RenderSettings st = base;
    st.spp = kOpenEndedPasses * pass_spp(integ);
    st.time_budget_s = budget;
    st.seed = seed;
    return st;
  };
  auto key_of = [&](const std::string& integ, double budget, uint64_t seed) {
    return nlohmann::json{{"scene", a.scene},  {"resolution", {W, H}}, {"integrator", integ},
                          {"budget_s", budget}, {"seed", seed},        {"max_depth", max_depth},
                          {"passes", kOpenEndedPasses}, {"pass_spp", pass_spp(integ)}};
  };
  if (mpi::world().rank == 0)
  fmt::print("tb compare: {} at {}x{}, integrators {}, checkpoints {} s (independent runs), seed {}, {} threads "
             "({} hardware threads)\n",
             a.scene, W, H, join(a.integrators, ","), join([&] {
               std::vector<std::string> s;
               for (double b : budgets) s.push_back(fmt::format("{:g}", b));
               return s;
             }(), "/"),
             a.seed, a.threads > 0 ? std::to_string(a.threads) : "all", hw);

  // The reference: given, or rendered now.
  std::string ref_path = a.reference;
  const bool ref_rendered = ref_path.empty();
  const double ref_budget = kReferenceBudgetFactor * a.time_s;

  // Under mpirun (docs/compare.md, "Under mpirun"): the renders (the reference when it is rendered,
  // then every integrator x checkpoint) are work items dealt round-robin to the ranks; each rank
  // renders its items exactly as one process would (same settings, seeds and keys) and the ranks
  // other than 0 send the files (EXR and JSON record) to rank 0, which writes them into DIR/ and
  // then runs the one-process comparison with --resume on: every item found is reloaded, an item
  // lost on its rank (an error) is rendered again by rank 0.
  bool resume = a.resume;
  const mpi::World& mw = mpi::world();
  if (mw.size > 1) {
    struct Item {
      const IntegratorInfo* info;
      std::string name, stem, label;
      double budget;
      uint64_t seed;
    };
    std::vector<Item> items;
    if (ref_rendered)
      items.push_back({find_integrator(kReferenceIntegrator), kReferenceIntegrator, (fs::path(out) / "reference").string(),
                       fmt::format("reference {} {:g} s", kReferenceIntegrator, ref_budget), ref_budget,
                       hash_values(a.seed, hash_string("reference"))});
    for (size_t ii = 0; ii < infos.size(); ++ii)
      for (size_t k = 0; k < budgets.size(); ++k)
        items.push_back({infos[ii], infos[ii]->name,
                         (fs::path(out) / "runs" / fmt::format("{}-{}", infos[ii]->name, k)).string(),
                         fmt::format("{} {:g} s ({}/{})", infos[ii]->name, budgets[k], k + 1, budgets.size()), budgets[k],
                         hash_values(a.seed, hash_string(infos[ii]->name), uint64_t(k))});
    nlohmann::json files = nlohmann::json::array();  // [stem, exr bytes, json bytes] of this rank's items
    ProgressLine rank_line(!a.no_progress && isatty(STDERR_FILENO) && mw.rank == 0);
    int done = 0, lost = 0;
    for (size_t j = static_cast<size_t>(mw.rank); j < items.size(); j += static_cast<size_t>(mw.size)) {
      const Item& it = items[j];
      const RenderSettings st = settings_for(it.name, it.budget, it.seed);
      try {
        const auto r = render_run(*world, *it.info, st, it.stem, key_of(it.name, it.budget, st.seed), a.resume, rank_line,
                                  it.label, interrupted);
        if (!r) break;  // interrupted
        ++done;
        if (mw.rank != 0) {
          const std::string exr = read_file(it.stem + ".exr");
          files.push_back({it.stem, nlohmann::json::binary(std::vector<uint8_t>(exr.begin(), exr.end())),
                           read_file(it.stem + ".json")});
        }
      } catch (const std::exception& e) {
        ++lost;
        fmt::print(stderr, "tb compare: rank {}: {} failed ({}); rank 0 renders it again\n", mw.rank, it.label, e.what());
      }
    }
    const std::vector<uint8_t> packed = nlohmann::json::to_cbor(nlohmann::json{{"files", files}, {"done", done}, {"lost", lost}});
    const std::vector<std::string> parts = mpi::gather(std::string(packed.begin(), packed.end()));
    if (mw.rank != 0) return 0;  // rank 0's exit status is the run's (mpirun reports a non-zero one)
    int total_done = done, total_lost = lost;
    for (size_t r = 1; r < parts.size(); ++r) {
      const nlohmann::json part = nlohmann::json::from_cbor(parts[r]);
      if (part.contains("error")) {
        // Every item dealt to that rank (j = r mod size) is lost.
        const size_t dealt = (items.size() + static_cast<size_t>(mw.size) - 1 - r) / static_cast<size_t>(mw.size);
        fmt::print(stderr, "tb compare under mpirun: rank {} of {} failed ({}); rank 0 renders its {} items again\n", r,
                   mw.size, part.at("error").get<std::string>(), dealt);
        total_lost += static_cast<int>(dealt);
      }
      total_done += part.at("done").get<int>();
      total_lost += part.at("lost").get<int>();
      for (const auto& f : part.at("files")) {
        const auto& bytes = f.at(1).get_binary();
        write_file_atomic(f.at(0).get<std::string>() + ".exr", std::string(bytes.begin(), bytes.end()));
        write_file_atomic(f.at(0).get<std::string>() + ".json", f.at(2).get<std::string>());
      }
    }
    fmt::print("under mpirun: {} renders over {} ranks ({} done, {} lost and rendered again on rank 0)\n", items.size(),
               mw.size, total_done, total_lost);
    resume = true;
  }
  if (ref_rendered) {
    ref_path = (fs::path(out) / "reference.exr").string();
    fmt::print("No --reference given: rendering a {} reference for {} x S = {:g} s to {} (its own noise, the rRMSE_ref "
               "column, limits what the comparison can resolve; pass a longer render with --reference)\n",
               kReferenceIntegrator, kReferenceBudgetFactor, ref_budget, ref_path);
    const RenderSettings st =
        settings_for(kReferenceIntegrator, ref_budget, hash_values(a.seed, hash_string("reference")));
    const auto r = render_run(*world, *find_integrator(kReferenceIntegrator), st,
                              (fs::path(out) / "reference").string(), key_of(kReferenceIntegrator, ref_budget, st.seed),
                              resume, line, fmt::format("reference {} {:g} s", kReferenceIntegrator, ref_budget),
                              interrupted);
    if (!r) {
      fmt::print("interrupted while rendering the reference (rerun with --resume to continue)\n");
      return 130;
    }
    fmt::print("  reference: {} passes in {:.2f} s{}\n", r->passes, r->seconds, r->resumed ? " (resumed)" : "");
  }
  const ExrImage ref = read_exr(ref_path);
  if (ref.width != W || ref.height != H) {
    fmt::print(stderr, "tb compare: reference {} is {}x{} but the scene renders at {}x{} (use --resolution {}x{})\n",
               ref_path, ref.width, ref.height, W, H, ref.width, ref.height);
    return 2;
  }
  std::vector<Rgb> ref_var;  // variance of the reference value itself: Welch-sample variance / count
  if (ref.variance && ref.count) {
    ref_var.resize(ref.rgb.size());
    for (size_t i = 0; i < ref_var.size(); ++i)
      ref_var[i] = (*ref.count)[i] > 0 ? (*ref.variance)[i] / double((*ref.count)[i]) : Rgb(0.0);
  } else {
    fmt::print("  note: the reference has no variance/count channels; its own noise is taken as 0\n");
  }
  const double floor = compare::reference_floor(ref.rgb, a.floor_fraction);
  write_png_preview((fs::path(out) / "images" / "reference.png").string(), W, H, ref.rgb, 0.0);

  // The runs.
  std::vector<IntegratorResult> results;
  bool stopped = false;
  for (size_t ii = 0; ii < infos.size() && !stopped; ++ii) {
    IntegratorResult res;
    res.name = infos[ii]->name;
    for (size_t k = 0; k < budgets.size(); ++k) {
      const RenderSettings st =
          settings_for(res.name, budgets[k], hash_values(a.seed, hash_string(res.name), uint64_t(k)));
      std::optional<Run> r;
      try {
        r = render_run(*world, *infos[ii], st, (fs::path(out) / "runs" / fmt::format("{}-{}", res.name, k)).string(),
                       key_of(res.name, budgets[k], st.seed), resume, line,
                       fmt::format("{} {:g} s ({}/{})", res.name, budgets[k], k + 1, budgets.size()), interrupted);
      } catch (const std::exception& e) {
        line.finish();
        res.error = e.what();
        fmt::print("  {}: failed: {}\n", res.name, res.error);
        break;
      }
      if (!r) {
        stopped = true;
        break;
      }
      res.errors.push_back(compare::relative_error(r->image, ref.rgb, ref_var, floor));
      const auto& e = res.errors.back();
      fmt::print("  {:<10} budget {:>7.3f} s: {:>8.3f} s, {:>7} passes, rRMSE {:.4g} (median |rel. error| {:.3g}){}{}\n",
                 res.name, budgets[k], r->seconds, r->passes, e.rrmse, e.median_abs_relative,
                 r->report.mutations.empty() ? "" : fmt::format(", {:.3g} mutations/s", r->report.mutations_per_second),
                 r->resumed ? " (resumed)" : "");
      std::fflush(stdout);
      r->image.clear();  // the final run's image is reloaded from its EXR for the previews
      res.runs.push_back(std::move(*r));
    }
    if (!stopped && res.error.empty()) {
      std::vector<stats::ConvergencePoint> pts;
      for (size_t k = 0; k < res.runs.size(); ++k) {
        stats::ConvergencePoint p;
        p.n = p.seconds = res.runs[k].seconds;
        p.rmse = res.errors[k].rrmse;
        p.replicates = std::max<int64_t>(1, std::llround(res.errors[k].effective_terms));
        pts.push_back(p);
      }
      try {
        res.fit = stats::fit_time_power_law(pts);
      } catch (const std::exception& e) {
        res.fit_error = e.what();
      }
    }
    results.push_back(std::move(res));
  }
  if (stopped) {
    fmt::print("interrupted: finished runs are kept in {}; rerun with --resume to continue\n",
               (fs::path(out) / "runs").string());
    return 130;
  }

  // Images of the renders at S and their relative error maps.
  for (auto& res : results) {
    if (res.runs.empty()) continue;
    const std::vector<Rgb> img = read_exr(res.runs.back().exr).rgb;
    write_png_preview((fs::path(out) / "images" / (res.name + ".png")).string(), W, H, img, 0.0);
    write_png_preview((fs::path(out) / "images" / (res.name + "-error.png")).string(), W, H,
                      compare::heat_colours(compare::relative_error_map(img, ref.rgb, floor), a.error_scale), 0.0);
  }

  // Tables, plots and results.json.
  Table summary{fmt::format("Equal time S = {:g} s, {}x{}", a.time_s, W, H),
                {"integrator", "time [s]", "rRMSE", "median rel.", "alpha [99% CI]", "efficiency", "passes",
                 "mutations/s", "acceptance"},
                {}};
  Table per_checkpoint{"rRMSE at each checkpoint (measured seconds in parentheses)", {"integrator"}, {}};
  for (double b : budgets) per_checkpoint.header.push_back(fmt::format("{:g} s", b));
  PlotSpec plot{"rRMSE against time", "wall time [s]", "rRMSE", true, true, {}, {}, 0, 1, 0, 1};
  PlotSpec eff_plot{"efficiency 1 / (rRMSE^2 t) against time", "wall time [s]", "efficiency", true, true, {}, {},
                    0, 1, 0, 1};
  nlohmann::json jint = nlohmann::json::array();
  for (const auto& res : results) {
    nlohmann::json ji = {{"name", res.name}, {"pass_spp", pass_spp(res.name)}};
    if (!res.error.empty()) {
      ji["error"] = res.error;
      summary.rows.push_back({res.name, "-", "failed: " + res.error, "-", "-", "-", "-", "-", "-"});
      jint.push_back(ji);
      continue;
    }
    nlohmann::json runs = nlohmann::json::array();
    PlotSeries s{res.name, {}, {}, {}, "linespoints"}, se{res.name, {}, {}, {}, "linespoints"};
    std::vector<std::string> cp_row{res.name};
    for (size_t k = 0; k < res.runs.size(); ++k) {
      const Run& r = res.runs[k];
      const compare::RelativeError& e = res.errors[k];
      const double eff = 1.0 / (e.rrmse * e.rrmse * r.seconds);
      nlohmann::json jr = {{"budget_s", r.budget},
                           {"seconds", r.seconds},
                           {"passes", r.passes},
                           {"rrmse", num(e.rrmse)},
                           {"rrmse_ref", num(e.rrmse_ref)},
                           {"mean_relative_error", num(e.mean_relative)},
                           {"median_abs_relative_error", num(e.median_abs_relative)},
                           {"channels", e.channels},
                           {"below_floor", e.below_floor},
                           {"nonfinite_pixel_channels", e.nonfinite},
                           {"effective_terms", num(e.effective_terms)},
                           {"efficiency", num(eff)},
                           {"nonfinite_samples", r.nonfinite_samples},
                           {"exr", fs::relative(r.exr, out).string()},
                           {"resumed", r.resumed}};
      if (!r.report.mutations.empty()) {
        jr["mutations"] = mutations_json(r.report);
        jr["mutations_total"] = r.report.mutations_total;
        jr["mutations_per_second"] = r.report.mutations_per_second;
      }
      runs.push_back(jr);
      s.x.push_back(r.seconds);
      s.y.push_back(e.rrmse);
      se.x.push_back(r.seconds);
      se.y.push_back(eff);
      cp_row.push_back(fmt::format("{:.4g} ({:.2f})", e.rrmse, r.seconds));
    }
    ji["runs"] = runs;
    plot.series.push_back(s);
    eff_plot.series.push_back(se);
    per_checkpoint.rows.push_back(cp_row);
    std::string alpha_text = "fit failed";
    if (res.fit) {
      const auto& f = *res.fit;
      ji["fit"] = {{"model", "rRMSE = C t^-alpha"}, {"converged", f.converged}, {"alpha", num(f.alpha)},
                   {"alpha_std_error", num(f.alpha_std_error)}, {"alpha_lo", num(f.alpha_lo)},
                   {"alpha_hi", num(f.alpha_hi)}, {"confidence", f.confidence}, {"log_c", num(f.log_c)},
                   {"reduced_chi2", num(f.reduced_chi2)}, {"chi2_p_value", num(f.chi2_p_value)},
                   {"rescaled", f.rescaled}, {"points", f.points}};
      alpha_text = fmt::format("{:.3f} [{:.3f}, {:.3f}]{}", f.alpha, f.alpha_lo, f.alpha_hi, f.converged ? "" : " (!)");
      const double t_lo = s.x.front(), t_hi = s.x.back();
      plot.series.push_back({res.name + fmt::format(" fit alpha={:.2f}", f.alpha), {t_lo, t_hi},
                             {f.predict(t_lo), f.predict(t_hi)}, {}, "lines"});
    } else {
      ji["fit"] = {{"error", res.fit_error}};
    }
    const Run& last = res.runs.back();
    const compare::RelativeError& el = res.errors.back();
    const double eff = 1.0 / (el.rrmse * el.rrmse * last.seconds);
    ji["final"] = {{"seconds", last.seconds},
                   {"rrmse", num(el.rrmse)},
                   {"efficiency", num(eff)},
                   {"passes", last.passes},
                   {"image", "images/" + res.name + ".png"},
                   {"error_map", "images/" + res.name + "-error.png"}};
    if (!last.report.mutations.empty()) ji["final"]["mutations_per_second"] = last.report.mutations_per_second;
    summary.rows.push_back({res.name, fmt::format("{:.2f}", last.seconds), fmt::format("{:.4g}", el.rrmse),
                            fmt::format("{:.3g}", el.median_abs_relative), alpha_text,
                            fmt::format("{:.4g}", eff), std::to_string(last.passes),
                            last.report.mutations.empty() ? "-" : fmt::format("{:.3g}", last.report.mutations_per_second),
                            acceptance_text(last.report)});
    jint.push_back(ji);
  }

  double rrmse_ref = 0.0;
  int64_t channels = 0, below = 0;
  for (const auto& res : results)
    if (!res.errors.empty()) {
      rrmse_ref = res.errors.back().rrmse_ref;
      channels = res.errors.back().channels;
      below = res.errors.back().below_floor;
      break;
    }
  std::string reproducer = fmt::format("tb compare {} --integrators {} --time {:g} --checkpoints {} --seed {}", a.scene,
                                       join(a.integrators, ","), a.time_s, a.checkpoints, a.seed);
  if (!a.reference.empty()) reproducer += " --reference " + a.reference;
  if (!a.resolution.empty()) reproducer += " --resolution " + a.resolution;
  if (a.floor_fraction != 0.01) reproducer += fmt::format(" --floor {:g}", a.floor_fraction);
  if (a.pass_spp > 0) reproducer += fmt::format(" --pass-spp {}", a.pass_spp);
  reproducer += " -o " + out;

  nlohmann::json j;
  j["kind"] = "tb compare scene";
  j["config"] = {
      {"scene", a.scene},
      {"integrators", a.integrators},
      {"time_s", a.time_s},
      {"checkpoints_s", budgets},
      {"checkpoint_mode", "independent runs, one per checkpoint, each with its own seed and budget t_k"},
      {"resolution", {W, H}},
      {"max_depth", max_depth},
      {"pass_spp", a.pass_spp},
      {"seed", a.seed},
      {"threads", a.threads},
      {"hardware_threads", hw},
      {"reference", ref_path},
      {"reference_rendered", ref_rendered},
      {"floor_fraction", a.floor_fraction},
      {"floor", floor},
      {"error_scale", a.error_scale},
      {"reproducer", reproducer},
      {"scene_description", world->description()}};
  if (ref_rendered) {
    j["config"]["reference_integrator"] = kReferenceIntegrator;
    j["config"]["reference_budget_s"] = ref_budget;
  }
  j["definitions"] = {
      {"rrmse", "sqrt(mean over pixel-channels c with R_c > floor of ((I_c - R_c) / R_c)^2); floor = floor_fraction * "
                "mean reference value"},
      {"rrmse_ref", "sqrt(mean over the same pixel-channels of Var(R_c) / R_c^2): the reference's own noise, included "
                    "in every rRMSE^2 in expectation"},
      {"efficiency", "1 / (rRMSE^2 * t), t = measured wall time of the run"},
      {"median_rel", "median over the same pixel-channels of |I_c - R_c| / R_c: robust to the outliers that can "
                     "dominate rRMSE (a diagnostic, not fitted)"},
      {"alpha", "Ceres fit of rRMSE = C t^-alpha over the checkpoints (validate/stats/convergence_fit.h), 99% interval; "
                "0.5 for an unbiased estimator with cost linear in samples"},
      {"error_map", fmt::format("per pixel mean over channels above the floor of |I - R| / R, hot colour ramp, white "
                                ">= {:g}, dark blue: below the floor", a.error_scale)}};
  j["reference_stats"] = {{"rrmse_ref", num(rrmse_ref)}, {"channels", channels}, {"below_floor", below},
                          {"image", "images/reference.png"}};
  j["integrators"] = jint;
  j["tables"] = nlohmann::json::array({summary, per_checkpoint});
  j["plots"] = nlohmann::json::array({plot, eff_plot});
  write_file_atomic((fs::path(out) / "results.json").string(), j.dump(1));
  write_compare_report(j, out);

  fmt::print("\n{}", compare::text_table(summary.header, summary.rows));
  fmt::print("\n{}", compare::text_table(per_checkpoint.header, per_checkpoint.rows));
  fmt::print("\nrRMSE over {} pixel-channels with reference > {:.4g} ({:g} x mean; {} left out); the reference's own "
             "noise rRMSE_ref = {:.4g}{}\n",
             channels, floor, a.floor_fraction, below, rrmse_ref,
             ref_rendered ? fmt::format(" ({} reference, {:g} s, rendered here)", kReferenceIntegrator, ref_budget)
                          : "");
  fmt::print("efficiency = 1 / (rRMSE^2 t); alpha: rRMSE = C t^-alpha over the checkpoints (99% interval).\n");
  fmt::print("Report: {}  Results: {}\n", (fs::path(out) / "index.html").string(),
             (fs::path(out) / "results.json").string());
  return 0;
}

}  // namespace tb

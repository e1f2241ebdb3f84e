// tb: the test bench program. Subcommands: check (validation suite), reproduce (a paper's
// canonical experiment), report (regenerate an HTML report from its JSON), render (a scene to
// OpenEXR), compare (statistical comparison of renders; equal-time comparison of integrators).
#include <atomic>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "app/cmd_compare.h"
#include "app/cli_domains.h"
#include "app/cmd_render.h"
#include "app/mpi_world.h"
#include "app/progress.h"
#include "lib/core/atomic_file.h"
#include "reports/compare_report.h"
#include "reports/html_report.h"
#include "validate/experiment.h"
#include "validate/registry.h"
#include "validate/runner.h"

namespace {

std::atomic<bool> g_interrupted{false};
void on_sigint(int) { g_interrupted = true; }

struct CheckArgs {
  std::vector<std::string> names;
  bool quick = false, full = false, list = false, resume = false, no_progress = false;
  uint64_t seed = 1;
  int attempt = 0;
  int calibrate = 0;
  std::string out = "reports/out/latest";
};

// `tb check --calibrate K`: the selection under K seeds, then the measured false-alarm rates.
int cmd_calibrate(const CheckArgs& a, const std::vector<const tb::Check*>& selected) {
  if (tb::mpi::world().size > 1) {
    fmt::print(stderr, "tb check --calibrate: run it without mpirun (one process)\n");
    return 2;
  }
  if (a.attempt != 0) {
    fmt::print(stderr, "tb check --calibrate: --attempt does not apply (every seed runs the normal policy)\n");
    return 2;
  }
  tb::RunOptions opt;
  opt.seed = a.seed;
  opt.full = a.full;
  opt.out_dir = a.out;
  opt.resume = a.resume;
  opt.interrupted = &g_interrupted;
  fmt::print("tb check --calibrate {}: {} checks, {} size, seeds {}..{}, results in {}\n", a.calibrate, selected.size(),
             a.full ? "full" : "quick", a.seed, a.seed + uint64_t(a.calibrate) - 1, a.out);
  const auto t0 = std::chrono::steady_clock::now();
  const nlohmann::json j = tb::calibrate_checks(selected, opt, a.calibrate, [&](int k, const tb::RunSummary& s) {
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print("seed {} ({}/{}): {} passed, {} failed{}; {:.0f} s so far\n", a.seed + uint64_t(k), k + 1, a.calibrate,
               s.passed, s.failed, s.resumed ? fmt::format(" ({} resumed)", s.resumed) : "", el);
    std::fflush(stdout);
  });
  const auto show = [](const nlohmann::json& r) {
    return fmt::format("{} of {} = {:.3g} [95% CI {:.3g}, {:.3g}]", r.value("count", 0), r.value("runs", 0),
                       r.value("rate", 0.0), r["ci95"][0].get<double>(), r["ci95"][1].get<double>());
  };
  fmt::print("\nSuite (negative controls aside): a check failed on {} seeds; a first attempt rejected on {}\n",
             show(j["suite_failed"]), show(j["suite_first_attempt_rejected"]));
  fmt::print("By construction: expected first-attempt rejections per run {:.3g} (sum of alpha); "
             "suite failure <= {:.3g} (sum of alpha^2: both attempts must reject)\n",
             j.value("expected_first_attempt_rejections_per_run", 0.0), j.value("bound_suite_failure", 0.0));
  int shown = 0;
  for (const auto& c : j["checks"]) {
    const bool control = c.value("negative_control", false);
    const auto& r = control ? c["missed"] : c["first_attempt_rejected"];
    if (r.value("count", 0) == 0) continue;
    if (shown++ == 0) fmt::print("Checks that rejected (first attempts; controls: missed):\n");
    fmt::print("  {:<56} alpha {:.3g}: {}{}\n", c.value("name", ""), c.value("alpha", 0.0), show(r),
               control ? " MISSED" : fmt::format(", failed {}", c["failed"].value("count", 0)));
  }
  if (shown == 0) fmt::print("No check rejected on any seed.\n");
  fmt::print("Results: {}\n", (std::filesystem::path(a.out) / "calibrate.json").string());
  return j.value("interrupted", false) ? 130 : 0;
}

// One line per effect kind: how many checks detect the target effect at 90% power, and the
// three weakest.
void print_power(const nlohmann::json& p) {
  const double target = p.value("target", 0.02);
  std::string unstated;
  int listed = 0;
  for (const auto& n : p.value("not_stated_checks", nlohmann::json::array())) {
    if (listed++ == 3) {
      unstated += ", ...";
      break;
    }
    unstated += (unstated.empty() ? "" : ", ") + n.get<std::string>();
  }
  fmt::print("Power (90%, first attempts, controls left out): {} checks state their minimum detectable effect, {} "
             "statistical checks do not{}; {} deterministic (a tolerance, no effect size)\n",
             p.value("stated", 0), p.value("not_stated", 0), unstated.empty() ? "" : " (" + unstated + ")",
             p.value("deterministic", 0));
  for (const auto& [kind, k] : p["kinds"].items()) {
    std::string weakest;
    int shown = 0;
    for (const auto& e : k["above_target"]) {
      if (shown++ == 3) break;
      weakest += fmt::format("{}{} {:.3g}% (needs {:.3g}x the samples)", shown > 1 ? ", " : "", e.value("name", ""),
                             100.0 * e.value("mde", 0.0), e.value("samples_scale_for_target", 0.0));
    }
    fmt::print("  {}: {} of {} detect {:.3g}% (median {:.3g}%){}{}\n", kind.empty() ? "(unnamed)" : kind,
               k.value("meet_target", 0), k.value("checks", 0), 100.0 * target, 100.0 * k.value("median", 0.0),
               weakest.empty() ? "" : "; weakest: ", weakest);
  }
}

int cmd_check(const CheckArgs& a) {
  const auto selected = tb::Registry::global().select(a.names);
  const bool quiet_rank = tb::mpi::world().rank != 0;  // under mpirun only rank 0 prints
  if (a.list) {
    if (quiet_rank) return 0;
    for (const tb::Check* c : selected)
      fmt::print("{:<52} {:<13} {}\n", c->name, c->kind == tb::CheckKind::kStatistical ? "statistical" : "deterministic",
                 c->description);
    return 0;
  }
  if (selected.empty()) {
    if (quiet_rank) return 2;
    fmt::print(stderr, "tb check: no check matches");
    for (const auto& n : a.names) fmt::print(stderr, " '{}'", n);
    fmt::print(stderr, " (see tb check --list)\n");
    return 2;
  }
  if (a.calibrate > 0) return cmd_calibrate(a, selected);
  // Under mpirun: rank r runs the checks whose index is r mod n; rank 0 alone prints, writes the
  // records, the results and the report (docs/checks-and-reports.md, "Under mpirun").
  const tb::mpi::World& world = tb::mpi::world();
  std::vector<const tb::Check*> mine;
  for (size_t i = 0; i < selected.size(); ++i)
    if (static_cast<int>(i % static_cast<size_t>(world.size)) == world.rank) mine.push_back(selected[i]);
  const bool progress = world.rank == 0 && !a.no_progress && isatty(STDERR_FILENO);
  tb::ProgressLine line(progress);
  tb::RunOptions opt;
  opt.seed = a.seed;
  opt.full = a.full;
  opt.attempt = a.attempt;
  opt.out_dir = world.rank == 0 ? a.out : std::string();
  opt.resume = a.resume;
  opt.interrupted = &g_interrupted;
  opt.on_progress = [&line](double f) { line.update(f); };
  opt.on_check = [&](size_t i, size_t n, const tb::Check& c, const nlohmann::json* rec) {
    if (!rec) {
      line.start(c.name);
      return;
    }
    line.finish();
    const auto& r = (*rec)["first"];
    const std::string verdict = rec->value("verdict", "fail");
    fmt::print("[{:>3}/{}] {:<6} {:<50} {:>7.2f}s  {}{}\n", i + 1, n,
               verdict == "pass" ? "PASS" : verdict == "fail" ? "FAIL" : "PASS*", c.name,
               r.value("seconds", 0.0), r.value("message", ""), rec->value("resumed", false) ? " (resumed)" : "");
    if (rec->contains("rerun"))
      fmt::print("           rerun (fresh seed, 4x samples): {}\n", (*rec)["rerun"].value("message", ""));
    std::fflush(stdout);
  };
  if (world.rank != 0) opt.on_check = {};
  std::signal(SIGINT, on_sigint);
  std::signal(SIGTERM, on_sigint);
  if (world.rank == 0)
    fmt::print("tb check: {} checks, {} size, seed {}, results in {}{}\n", selected.size(), a.full ? "full" : "quick",
               a.seed, a.out, world.size > 1 ? fmt::format(" ({} MPI ranks)", world.size) : "");
  tb::RunSummary s = tb::run_checks(mine, opt);
  if (world.size > 1) {
    const nlohmann::json part = {{"checks", s.results["checks"]}, {"interrupted", s.interrupted}, {"resumed", s.resumed}};
    const std::vector<std::string> parts = tb::mpi::gather(part.dump());
    if (world.rank != 0) return tb::mpi::broadcast(0);
    std::map<std::string, nlohmann::json> by_name;
    tb::RunSummary merged;
    for (const std::string& text : parts) {
      const nlohmann::json j = nlohmann::json::parse(text);
      merged.interrupted = merged.interrupted || j.value("interrupted", false);
      merged.resumed += j.value("resumed", size_t{0});
      for (const auto& rec : j["checks"]) by_name[rec.value("name", "")] = rec;
    }
    merged.results["config"] = s.results["config"];
    merged.results["config"]["checks"] = selected.size();
    merged.results["config"]["mpi_ranks"] = world.size;
    merged.results["checks"] = nlohmann::json::array();
    for (size_t i = 0; i < selected.size(); ++i) {  // the selection's order, whatever rank ran each
      const tb::Check* c = selected[i];
      const auto it = by_name.find(c->name);
      if (it == by_name.end()) continue;  // not reached: a rank was interrupted
      if (i % static_cast<size_t>(world.size) != 0)  // rank 0's own records are written already
        tb::write_file_atomic((std::filesystem::path(a.out) / "records" / (c->name + ".json")).string(),
                              it->second.dump(1));
      (it->second.value("passed", false) ? merged.passed : merged.failed) += 1;
      merged.results["checks"].push_back(it->second);
    }
    merged.results["passed"] = merged.passed;
    merged.results["failed"] = merged.failed;
    merged.results["interrupted"] = merged.interrupted;
    s = std::move(merged);
  }

  s.results["power"] = tb::power_summary(s.results["checks"]);
  const std::string results_path = (std::filesystem::path(a.out) / "results.json").string();
  tb::write_file_atomic(results_path, s.results.dump(1));
  tb::write_check_report(s.results, a.out);
  fmt::print("\n{} passed, {} failed{}{}. Report: {}\n", s.passed, s.failed,
             s.resumed ? fmt::format(" ({} resumed)", s.resumed) : "",
             s.interrupted ? " (interrupted: rerun with --resume to continue)" : "",
             (std::filesystem::path(a.out) / "index.html").string());
  print_power(s.results["power"]);
  if (s.failed > 0) {
    fmt::print("Failures, with the command that reproduces each:\n");
    for (const auto& rec : s.results["checks"]) {
      if (rec.value("passed", false)) continue;
      fmt::print("  {}: {}\n    {}\n", rec.value("name", ""), rec["first"].value("message", ""),
                 rec["first"].value("reproducer", ""));
      if (rec.contains("rerun"))
        fmt::print("    rerun: {}\n    {}\n", rec["rerun"].value("message", ""), rec["rerun"].value("reproducer", ""));
    }
  }
  return tb::mpi::broadcast(s.interrupted ? 130 : s.failed > 0 ? 1 : 0);
}

struct ReproduceArgs {
  std::string name;
  bool quick = false, full = false, list = false, no_progress = false;
  uint64_t seed = 1;
  std::string out;
};

int cmd_reproduce(const ReproduceArgs& a) {
  const auto& reg = tb::ExperimentRegistry::global();
  if (a.list || a.name.empty()) {
    for (const auto& e : reg.experiments()) fmt::print("{:<24} {}\n", e.name, e.description);
    return a.list ? 0 : 2;
  }
  const tb::Experiment* e = reg.find(a.name);
  if (!e) {
    fmt::print(stderr, "tb reproduce: no experiment named '{}' (see tb reproduce --list)\n", a.name);
    return 2;
  }
  // An experiment runs its replicates in one process: under mpirun every rank would run all of
  // them and write the same files at once. Refused, until replicates are dealt over ranks.
  if (tb::mpi::world().size > 1) {
    if (tb::mpi::world().rank == 0)
      fmt::print(stderr, "tb reproduce: not spread over MPI ranks (each of the {} ranks would run the whole "
                         "experiment and write the same files); run it without mpirun\n",
                 tb::mpi::world().size);
    return 2;
  }
  const std::string out = a.out.empty() ? "reports/out/" + a.name : a.out;
  tb::ProgressLine line(!a.no_progress && isatty(STDERR_FILENO));
  line.start(a.name);
  tb::ExperimentContext ctx;
  ctx.seed = a.seed;
  ctx.full = a.full;
  ctx.progress = [&line](double f) { line.update(f); };
  const auto t0 = std::chrono::steady_clock::now();
  tb::ExperimentReport rep = e->run(ctx);
  line.finish();
  nlohmann::json j = rep;
  j["config"] = {{"experiment", a.name}, {"seed", a.seed}, {"full", a.full},
                 {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()},
                 {"reproducer", fmt::format("tb reproduce {} --seed {} {}", a.name, a.seed, a.full ? "--full" : "--quick")}};
  tb::write_file_atomic((std::filesystem::path(out) / "report.json").string(), j.dump(1));
  tb::write_experiment_report(a.name, j, out);
  for (const auto& c : rep.claims) fmt::print("  {}\n", c);
  fmt::print("{}: {}. Report: {}\n", a.name, rep.passed ? "claims held" : "A CLAIM FAILED",
             (std::filesystem::path(out) / "index.html").string());
  return rep.passed ? 0 : 1;
}

int cmd_report(const std::string& json_path, const std::string& out) {
  const nlohmann::json j = nlohmann::json::parse(tb::read_file(json_path));
  const std::string dir = out.empty() ? std::filesystem::path(json_path).parent_path().string() : out;
  if (j.value("kind", "") == "tb compare scene")
    tb::write_compare_report(j, dir);
  else if (j.contains("checks"))
    tb::write_check_report(j, dir);
  else
    tb::write_experiment_report(j["config"].value("experiment", "experiment"), j, dir);
  fmt::print("Report: {}\n", (std::filesystem::path(dir) / "index.html").string());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  tb::mpi::init(&argc, &argv);  // only under an MPI launcher
  struct Finalize {
    ~Finalize() { tb::mpi::finalize(); }
  } finalize_mpi;
  CLI::App app{"tb: a test bench for Monte Carlo and MCMC light transport estimators"};
  app.require_subcommand(1);

  CheckArgs ca;
  auto* check = app.add_subcommand("check", "Run validation checks; exits non-zero when a check fails");
  check->add_option("names", ca.names, "Checks to run: full names, group prefixes (core.warp) or globs (*chi2)");
  auto* q = check->add_flag("--quick", ca.quick, "Quick sample sizes (default)");
  check->add_flag("--full", ca.full, "Full sample sizes of docs/validation.md")->excludes(q);
  check->add_option("--seed", ca.seed, "Run seed; each check derives its own scrambled seed from it")
      ->check(tb::cli::unsigned_integer());
  check->add_option("--out", ca.out, "Output folder for results.json, records/ and index.html")->capture_default_str();
  check->add_option("--attempt", ca.attempt, "Run the k-th rerun directly (fresh seed, 4x samples); for reproducers")
      ->check(CLI::Range(0, 1));
  check->add_option("--calibrate", ca.calibrate,
                    "Run the selection under K seeds (--seed, --seed + 1, ...) and report each check's and the suite's "
                    "measured false-alarm rate with 95% intervals (OUT/calibrate.json; resumable with --resume)")
      ->check(CLI::PositiveNumber);
  check->add_flag("--list", ca.list, "List the checks (matching NAMES) and exit");
  check->add_flag("--resume", ca.resume, "Reuse finished checks of an interrupted run with the same seed and size");
  check->add_flag("--no-progress", ca.no_progress, "No progress line on stderr");

  ReproduceArgs ra;
  auto* repro = app.add_subcommand("reproduce", "Run a paper's canonical experiment and write its report");
  repro->add_option("name", ra.name, "Experiment name (see --list)");
  auto* rq = repro->add_flag("--quick", ra.quick, "Quick size (default)");
  repro->add_flag("--full", ra.full, "Paper-scale replicate counts")->excludes(rq);
  repro->add_option("--seed", ra.seed, "Run seed")
      ->check(tb::cli::unsigned_integer());
  repro->add_option("--out", ra.out, "Output folder (default reports/out/NAME)");
  repro->add_flag("--list", ra.list, "List the experiments and exit");
  repro->add_flag("--no-progress", ra.no_progress, "No progress line on stderr");

  tb::RenderArgs rargs;
  auto* render = app.add_subcommand("render", "Render a scene file to OpenEXR (+ PNG preview, JSON record)");
  render->add_option("scene", rargs.scene, "Scene file (JSON, or Mitsuba XML by content; docs/scene.md)");
  render->add_option("--integrator", rargs.integrator, "Integrator name (see --list)")->capture_default_str();
  render->add_option("--spp", rargs.spp, "Samples per pixel (default: the scene's, else 16); with --time, per pass (default 1, PSS MCMC: 65536 / pixels)")
      ->check(tb::cli::integer_at_least(1));
  render->add_option("--passes", rargs.passes, "Welch samples per pixel (spp is split over them)")->capture_default_str()
      ->check(tb::cli::integer_at_least(1));
  render->add_option("--time", rargs.time_s, "Time budget in seconds: render passes until it runs out")
      ->check(tb::cli::positive_number());
  render->add_option("--seed", rargs.seed, "Seed")
      ->check(tb::cli::unsigned_integer());
  render->add_option("--threads", rargs.threads, "Worker threads (0: all cores)")
      ->check(tb::cli::integer_at_least(0));
  render->add_option("-o,--out", rargs.out, "Output EXR path")->capture_default_str();
  render->add_option("--resolution", rargs.resolution, "WxH: override the scene camera's resolution");
  render->add_option("--param", rargs.params,
                     "NAME=VALUE: an integrator parameter (repeatable; --list shows each integrator's)");
  render->add_option("--partition", rargs.partition,
                     "ramlt-lens / ramlt-multichain: region partition of the adaptation: fixed, global, grid, quadtree "
                     "(screen space), and for ramlt-multichain grid4d, quadtree4d (screen grid x direction at the first "
                     "non-specular vertex); default grid");
  render->add_flag("--list", rargs.list, "List the integrators and exit");
  render->add_flag("--no-progress", rargs.no_progress, "No progress line on stderr");

  tb::CompareArgs cmpa;
  auto* compare = app.add_subcommand(
      "compare",
      "Compare two renders statistically (A.exr B.exr: tiled or per-pixel Welch t-test, Stouffer, sum z^2; exit 1 if they "
      "differ), or integrators at equal time on a scene (SCENE --integrators A,B --time S: rRMSE against time, "
      "fitted rates, efficiency, HTML report; docs/compare.md)");
  compare->add_option("inputs", cmpa.inputs,
                      "A.exr B.exr (EXRs written by tb render; .pfm images are exact references), A.exr with "
                      "--reference-mean/--reference-variance, or one scene file")
      ->required()->expected(1, 2);
  const std::vector<std::string> compare_image_opts = {"--alpha", "--json", "--reference-mean", "--reference-variance",
                                                       "--skew-correction", "--test", "--tile"};
  compare->add_option("--reference-mean", cmpa.reference_mean,
                      "A.exr: the reference's mean image (.pfm or .exr), compared with A instead of B");
  compare->add_option("--reference-variance", cmpa.reference_variance,
                      "A.exr: the per-pixel variance of the reference's mean (.pfm or .exr; squared standard error)");
  compare->add_option("--alpha", cmpa.alpha, "A.exr B.exr: significance level of the whole comparison")
      ->capture_default_str()
      ->check(tb::cli::number_in(0, false, 1, false));
  compare->add_option("--json", cmpa.json_out, "A.exr B.exr: write the full result to this JSON file");
  compare->add_flag("--skew-correction", cmpa.skew_correction,
                    "A.exr B.exr: Hall's skewness transformation of each pixel's t (experimental; docs/integrator.md)");
  compare->add_option("--test", cmpa.test,
                      "A.exr B.exr: tiled (default: Welch test per k x k tile, k chosen from the stored skewness so "
                      "that heavy tails cannot shift Stouffer's Z by more than 0.25; docs/statistics.md) or pixel")
      ->check(CLI::IsMember({"tiled", "pixel"}))
      ->capture_default_str();
  compare->add_option("--tile", cmpa.tile, "A.exr B.exr, --test tiled: tile size K (default: chosen from the skewness)")
      ->check(tb::cli::integer_at_least(1));
  tb::CompareSceneArgs& cs = cmpa.scene;
  const std::vector<std::string> compare_scene_opts = {"--integrators", "--time",  "--reference",   "--out",
                                                       "--checkpoints", "--resolution", "--seed", "--threads", "--pass-spp",
                                                       "--floor",       "--error-scale", "--resume", "--no-progress"};
  compare->add_option("--integrators", cs.integrators, "SCENE: integrators to compare, comma separated (tb render --list)")
      ->delimiter(',');
  compare->add_option("--time", cs.time_s, "SCENE: time budget S in seconds of the largest checkpoint")
      ->check(tb::cli::positive_number());
  compare->add_option("--reference", cs.reference,
                      "SCENE: reference EXR (default: render one with bdpt for 4 x S, announced on stdout)");
  compare->add_option("-o,--out", cs.out, "SCENE: output folder (default reports/out/compare-<scene name>)");
  compare->add_option("--checkpoints", cs.checkpoints, "SCENE: K independent runs with budgets S/2^(K-1) ... S/2, S")
      ->capture_default_str()
      ->check(tb::cli::integer_in(3, 16));
  compare->add_option("--resolution", cs.resolution, "SCENE: WxH, overrides the scene camera's resolution");
  compare->add_option("--seed", cs.seed, "SCENE: seed (each run derives its own)")->capture_default_str()
      ->check(tb::cli::unsigned_integer());
  compare->add_option("--pass-spp", cs.pass_spp,
                      "SCENE: samples (MCMC: mutations) per pixel per pass; 0: 1, or enough to outweigh the PSS "
                      "bootstrap")->capture_default_str()
      ->check(tb::cli::integer_at_least(0));
  compare->add_option("--threads", cs.threads, "SCENE: worker threads (0: all cores)")->capture_default_str()
      ->check(tb::cli::integer_at_least(0));
  compare->add_option("--floor", cs.floor_fraction,
                      "SCENE: leave out pixel-channels whose reference is below this fraction of its mean")
      ->capture_default_str()
      ->check(tb::cli::number_in(0, true, 1, false));
  compare->add_option("--error-scale", cs.error_scale, "SCENE: relative error shown white in the error maps")
      ->capture_default_str()
      ->check(tb::cli::positive_number());
  compare->add_flag("--resume", cs.resume, "SCENE: reuse the runs of an interrupted invocation with the same settings");
  compare->add_flag("--no-progress", cs.no_progress, "SCENE: no progress line on stderr");

  std::string report_json, report_out;
  auto* report = app.add_subcommand("report", "Regenerate an HTML report from results.json or report.json");
  report->add_option("json", report_json, "results.json (tb check, tb compare SCENE) or report.json (tb reproduce)")->required()
      ->check(CLI::ExistingFile);
  report->add_option("--out", report_out, "Output folder (default: the JSON file's folder)");

  // Every parse error (unknown option, unconvertible or out-of-domain value) exits with status 2;
  // --help exits 0.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*check) return cmd_check(ca);
    if (*repro) return cmd_reproduce(ra);
    if (*render) {
      if (!rargs.list && rargs.scene.empty()) {
        fmt::print(stderr, "tb render: a scene file is required\n");
        return 2;
      }
      std::signal(SIGINT, on_sigint);
      return tb::cmd_render(rargs, &g_interrupted);
    }
    if (*report) return cmd_report(report_json, report_out);
    if (*compare) {
      for (const auto& o : compare_image_opts)
        if (compare->count(o) > 0) cmpa.image_options_given.push_back(o);
      for (const auto& o : compare_scene_opts)
        if (compare->count(o) > 0) cmpa.scene_options_given.push_back(o);
      std::signal(SIGINT, on_sigint);
      return tb::cmd_compare(cmpa, &g_interrupted);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "tb: error: {}\n", e.what());
    return 2;
  }
  return 0;
}

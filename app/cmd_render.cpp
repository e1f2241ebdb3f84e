#include "app/cmd_render.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <unistd.h>

#include "app/progress.h"
#include "app/scene_loading.h"
#include "lib/core/atomic_file.h"
#include "lib/core/parallel.h"
#include "lib/film/exr_io.h"
#include "lib/film/png_preview.h"
#include "lib/integrator/path_filter.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/scene_loader.h"

namespace tb {

int cmd_render(const RenderArgs& a, const std::atomic<bool>* interrupted) {
  if (a.list) {
    for (const auto& i : integrators()) {
      fmt::print("{:<12} {}\n", i.name, i.description);
      for (const auto& p : i.parameters) fmt::print("{:<12}   --param {}=...  {}\n", "", p.name, p.description);
    }
    return 0;
  }
  const IntegratorInfo* integ = find_integrator(a.integrator);
  if (!integ) {
    std::string names;
    for (const auto& i : integrators()) names += (names.empty() ? "" : ", ") + i.name;
    fmt::print(stderr, "tb render: unknown integrator '{}' (known: {})\n", a.integrator, names);
    return 2;
  }
  std::map<std::string, double> params;
  for (const std::string& kv : a.params) {
    const size_t eq = kv.find('=');
    double v = 0.0;
    size_t used = 0;
    bool ok = eq != std::string::npos && eq > 0;
    if (ok) {
      try {
        v = std::stod(kv.substr(eq + 1), &used);
      } catch (const std::exception&) {
        ok = false;
      }
      ok = ok && used == kv.size() - eq - 1;
    }
    if (!ok) {
      fmt::print(stderr, "tb render: --param '{}' is not NAME=NUMBER\n", kv);
      return 2;
    }
    params[kv.substr(0, eq)] = v;
  }
  if (const std::string err = validate_params(*integ, params); !err.empty()) {
    fmt::print(stderr, "tb render: {}\n", err);
    return 2;
  }
  const bool ramlt = a.integrator.rfind("ramlt-", 0) == 0;
  if (!a.partition.empty() && !ramlt) {
    fmt::print(stderr, "tb render: --partition applies to the ramlt-* integrators only\n");
    return 2;
  }
  const auto t_load = std::chrono::steady_clock::now();
  std::unique_ptr<World> world = load_scene_file(a.scene, a.resolution);
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_load).count();

  RenderSettings st = fixed_work_settings(*world, a.spp, a.passes, a.seed);
  st.time_budget_s = a.time_s;
  st.interrupted = interrupted;
  st.params = params;
  RunReport report;
  st.report = &report;
  if (a.time_s > 0) {  // open-ended passes of default_pass_spp each, until the budget runs out
    st.passes = int64_t{1} << 24;
    const int64_t n = a.spp > 0 ? std::max<int64_t>(1, a.spp)
                                : default_pass_spp(a.integrator, world->camera().width() * world->camera().height());
    st.spp = st.passes * n;
  }
  ProgressLine line(!a.no_progress && isatty(STDERR_FILENO));
  line.start(fmt::format("{} {}", a.integrator, std::filesystem::path(a.scene).filename().string()));
  const auto t_start = std::chrono::steady_clock::now();
  st.progress = [&](double f) {
    // With a time budget the pass count is open-ended: show the fraction of the budget used.
    if (a.time_s > 0)
      f = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count() / a.time_s;
    line.update(f);
  };

  ThreadLimit limit(static_cast<size_t>(std::max(0, a.threads)));
  Film film(world->camera().width(), world->camera().height());
  const auto t0 = std::chrono::steady_clock::now();
  // ramlt-*: the driver directly, for the partition option and the per-region maps.
  std::optional<path_space::RamltRegionMaps> ramlt_maps;
  int64_t passes = 0;
  if (ramlt) {
    path_space::RamltOptions ro;
    if (a.integrator == "ramlt-multichain") ro.perturbation = path_space::RamltPerturbation::kMultiChain;
    if (!a.partition.empty()) ro.partition = a.partition;
    ro = path_space::apply_ramlt_params(ro, st.params);
    const path_space::RamltStats rs = path_space::run_ramlt(*world, st, film, ro);
    for (const auto& m : rs.mlt.mutations) report.mutations.push_back({m.name, m.proposed, m.accepted, m.errors});
    report.mutations_total = rs.mlt.mutations_total;
    report.mutations_per_second = rs.mlt.mutations_per_second();
    ramlt_maps = rs.maps;
    passes = rs.mlt.chains;
  } else {
    passes = integ->render(*world, st, film);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  line.finish();

  const ExrImage img = exr_image_from_welch(film.welch());
  write_exr(a.out, img);
  const std::string png = std::filesystem::path(a.out).replace_extension(".png").string();
  write_png_preview(png, film.width(), film.height(), film.mean_image(), 0.0);
  const int64_t spp_done = passes * std::max<int64_t>(1, st.spp / std::max<int64_t>(1, st.passes));
  nlohmann::json rec = {{"scene", a.scene},
                        {"integrator", a.integrator},
                        {"seed", a.seed},
                        {"passes", passes},
                        {"max_depth", st.max_depth},
                        {"params", params},
                        {"resolution", {film.width(), film.height()}},
                        {"spp", spp_done},
                        {"seconds", seconds},
                        {"load_seconds", load_s},
                        {"nonfinite_samples", film.nonfinite().count()},
                        {"interrupted", interrupted && interrupted->load()},
                        {"scene_description", world->description()}};
  if (!report.mutations.empty()) {
    nlohmann::json m = nlohmann::json::array();
    for (const auto& r : report.mutations)
      m.push_back({{"name", r.name}, {"proposed", r.proposed}, {"accepted", r.accepted}, {"acceptance", r.acceptance()},
                   {"errors", r.errors}});
    rec["mutations"] = m;
    rec["mutations_total"] = report.mutations_total;
    rec["mutations_per_second"] = report.mutations_per_second;
    if (report.startup_seconds > 0) rec["startup_seconds"] = report.startup_seconds;
  }
  if (ramlt_maps) {
    const std::string base = std::filesystem::path(a.out).replace_extension("").string();
    path_space::write_ramlt_maps(*ramlt_maps, base);
    rec["ramlt_maps"] = base + ".ramlt.json";
    rec["partition"] = ramlt_maps->partition;
    rec["ramlt_regions"] = ramlt_maps->regions;
  }
  write_file_atomic(std::filesystem::path(a.out).replace_extension(".json").string(), rec.dump(1));
  fmt::print("{}: {}x{}, {} passes, {} spp in {:.2f} s ({:.3g} samples/s); {} non-finite samples rejected\n", a.out,
             film.width(), film.height(), passes, spp_done, seconds,
             static_cast<double>(spp_done) * static_cast<double>(film.pixel_count()) / seconds,
             film.nonfinite().count());
  if (!report.mutations.empty()) {
    fmt::print("{} mutations, {:.3g} mutations/s; acceptance:", report.mutations_total, report.mutations_per_second);
    int64_t errors = 0;
    for (const auto& r : report.mutations) {
      fmt::print(" {} {:.3f} ({} proposed)", r.name, r.acceptance(), r.proposed);
      errors += r.errors;
    }
    fmt::print("\n");
    if (errors > 0)
      fmt::print("{} proposed moves with a stated forward density of 0 or non-finite Hastings terms (never accepted): "
                 "a mutation misstates its density\n", errors);
  }
  if (a.integrator == "pf1") {
    const Pf1Timing t = pf1_last_timing();
    if (t.passes > 0)
      fmt::print("pf1: {:.3f} s per pass in the prefix pass, {:.3f} s per pass filtering (kernels, weights, suffixes); "
                 "mean kernel {:.2f} prefixes\n",
                 t.prefix_seconds / double(t.passes), t.filter_seconds / double(t.passes), t.mean_members);
  }
  if (film.nonfinite().count() > 0)
    fmt::print("{} (replay: tb render {} --integrator {} --seed {})\n", film.nonfinite().summary(), a.scene,
               a.integrator, a.seed);
  return 0;
}

}  // namespace tb

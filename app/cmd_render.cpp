#include "app/cmd_render.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <unistd.h>

#include "app/mpi_world.h"
#include "app/progress.h"
#include "app/scene_loading.h"
#include "lib/core/atomic_file.h"
#include "lib/core/parallel.h"
#include "lib/film/exr_io.h"
#include "lib/film/pass_tiles.h"
#include "lib/film/png_preview.h"
#include "lib/integrator/path_filter.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/scene_loader.h"

namespace tb {
namespace {

// Under mpirun (docs/checks-and-reports.md, "tb render under mpirun"): rank r of n renders the
// passes [P r / n, P (r + 1) / n) of the P passes (path-space MLT: chains) and keeps each pass's
// Welch samples as its film closes it; rank 0 adds the other ranks' passes, in rank and pass order,
// to its own film's sums. Every pass is a pure function of (seed, pass index) and the sums are
// accumulated in pass order exactly as one process does, so the image is bit-identical to a
// one-process run. A rank's message: an 8-byte length, a JSON header (counts, mutation reports),
// then its passes as raw doubles (pixels x 3 per pass).
struct RankPart {
  nlohmann::json header;
  std::vector<double> passes;  // pass-major, pixel-major, RGB
};

std::string pack_part(const nlohmann::json& header, const std::vector<double>& passes) {
  const std::string h = header.dump();
  const uint64_t n = h.size();
  std::string out(sizeof n, '\0');
  std::memcpy(out.data(), &n, sizeof n);
  out += h;
  const size_t at = out.size();
  out.resize(at + passes.size() * sizeof(double));
  if (!passes.empty()) std::memcpy(out.data() + at, passes.data(), passes.size() * sizeof(double));
  return out;
}

RankPart unpack_part(const std::string& s) {
  uint64_t n = 0;
  if (s.size() < sizeof n) throw std::runtime_error("tb render under mpirun: truncated message from a rank");
  std::memcpy(&n, s.data(), sizeof n);
  if (s.size() < sizeof n + n || (s.size() - sizeof n - n) % sizeof(double) != 0)
    throw std::runtime_error("tb render under mpirun: malformed message from a rank");
  RankPart p;
  p.header = nlohmann::json::parse(s.substr(sizeof n, n));
  p.passes.resize((s.size() - sizeof n - n) / sizeof(double));
  if (!p.passes.empty()) std::memcpy(p.passes.data(), s.data() + sizeof n + n, p.passes.size() * sizeof(double));
  return p;
}

// Rank 0 prints every failed rank's message (rank order) and the run fails; `parts` from the gather.
int report_rank_failures(const std::vector<std::string>& parts, int size) {
  int failed = 0;
  for (size_t r = 0; r < parts.size(); ++r) {
    const RankPart part = unpack_part(parts[r]);
    if (!part.header.contains("error")) continue;
    ++failed;
    fmt::print(stderr, "tb render under mpirun: rank {} of {} failed: {}\n", r, size,
               part.header.at("error").get<std::string>());
  }
  if (failed > 0) fmt::print(stderr, "tb render under mpirun: {} of {} ranks failed; no image written\n", failed, size);
  return failed;
}

}  // namespace

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
  const mpi::World& mw = mpi::world();
  const bool distributed = mw.size > 1;
  if (distributed && a.time_s > 0) {
    if (mw.rank == 0)
      fmt::print(stderr, "tb render: --time is refused under mpirun (a time budget makes the passes each rank "
                         "renders depend on its speed); give --spp and --passes\n");
    return 2;
  }
  const auto t_load = std::chrono::steady_clock::now();
  // Under mpirun a rank that fails (a scene missing on its machine, an exception while rendering)
  // still takes part in the one gather, with its message instead of passes: rank 0 names it and
  // every rank returns, instead of the others waiting for it forever.
  std::unique_ptr<World> world;
  try {
    world = load_scene_file(a.scene, a.resolution);
  } catch (const std::exception& e) {
    if (!distributed) throw;
    const std::vector<std::string> parts = mpi::gather(pack_part({{"error", e.what()}}, {}));
    // Only rank 0's exit status may be non-zero: mpirun ends the whole job at the first non-zero
    // one, which could cut rank 0 off before it has named the failed ranks.
    if (mw.rank != 0) return 0;
    report_rank_failures(parts, mw.size);
    return 1;
  }
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
  ProgressLine line(!a.no_progress && isatty(STDERR_FILENO) && mw.rank == 0);
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
  // Under mpirun: this rank's range of the passes, and (ranks > 0) its closed passes kept for rank 0.
  std::vector<double> my_passes;
  if (distributed) {
    const int64_t P = std::max<int64_t>(1, st.passes);
    st.first_pass = P * mw.rank / mw.size;
    st.pass_count = P * (mw.rank + 1) / mw.size - st.first_pass;
    const double bytes = static_cast<double>((P + mw.size - 1) / mw.size) * static_cast<double>(film.pixel_count()) * 24.0;
    if (bytes > 1.5e9) {
      if (mw.rank == 0)
        fmt::print(stderr, "tb render under mpirun: {:.3g} GB of pass images per rank exceeds the 1.5 GB a message "
                           "may hold; use fewer passes or more ranks\n", bytes / 1e9);
      return 2;
    }
    if (mw.rank != 0) my_passes.reserve(static_cast<size_t>(st.pass_count * film.pixel_count() * 3));
  }
  // Per-pass tile sums for tb compare's pass-tile test (lib/film/pass_tiles.h), in pass order.
  PassTiles tiles(film.width(), film.height());
  film.set_pass_observer([&](const std::vector<Rgb>& pass) {
    tiles.add_pass(pass);
    if (distributed && mw.rank != 0)
      for (const Rgb& v : pass) my_passes.insert(my_passes.end(), {v[0], v[1], v[2]});
  });
  const auto t0 = std::chrono::steady_clock::now();
  // ramlt-*: the driver directly, for the partition option and the per-region maps.
  std::optional<path_space::RamltRegionMaps> ramlt_maps;
  int64_t passes = 0;
  std::string rank_error;
  try {
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
  } catch (const std::exception& e) {
    if (!distributed) throw;
    rank_error = e.what();
  }
  WelchImage welch = film.welch();
  int64_t nonfinite = film.nonfinite().count();
  if (distributed) {
    nlohmann::json h = {{"passes", passes}, {"nonfinite", nonfinite}, {"mutations_total", report.mutations_total}};
    h["mutations"] = nlohmann::json::array();
    for (const auto& m : report.mutations) h["mutations"].push_back({m.name, m.proposed, m.accepted, m.errors});
    if (!rank_error.empty()) {
      h = {{"error", rank_error}};
      my_passes.clear();
    }
    const std::vector<std::string> parts = mpi::gather(pack_part(h, my_passes));
    // Rank 0's exit status is the run's (mpirun reports a non-zero one); the other ranks are done, so
    // nothing after this point can leave them waiting on rank 0.
    if (mw.rank != 0) return 0;
    if (report_rank_failures(parts, mw.size) > 0) return 1;
    {
      const size_t px = welch.pixels();
      for (size_t r = 1; r < parts.size(); ++r) {
        const RankPart part = unpack_part(parts[r]);
        const int64_t n = part.header.at("passes").get<int64_t>();
        if (part.passes.size() != static_cast<size_t>(n) * px * 3)
          throw std::runtime_error(fmt::format("tb render under mpirun: rank {} sent {} values for {} passes", r,
                                               part.passes.size(), n));
        std::vector<Rgb> pass(px);
        for (int64_t j = 0; j < n; ++j) {  // in pass order, as one process adds them
          for (size_t i = 0; i < px; ++i) {
            const double* v = part.passes.data() + (static_cast<size_t>(j) * px + i) * 3;
            pass[i] = Rgb(v[0], v[1], v[2]);
            welch.add(i, pass[i]);
          }
          tiles.add_pass(pass);
        }
        passes += n;
        nonfinite += part.header.at("nonfinite").get<int64_t>();
        report.mutations_total += part.header.at("mutations_total").get<int64_t>();
        for (const auto& m : part.header.at("mutations")) {
          const std::string name = m.at(0).get<std::string>();
          auto it = std::find_if(report.mutations.begin(), report.mutations.end(),
                                 [&](const MutationReport& x) { return x.name == name; });
          if (it == report.mutations.end()) it = report.mutations.insert(report.mutations.end(), MutationReport{name});
          it->proposed += m.at(1).get<int64_t>();
          it->accepted += m.at(2).get<int64_t>();
          it->errors += m.at(3).get<int64_t>();
        }
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (distributed && report.mutations_total > 0)
    report.mutations_per_second = static_cast<double>(report.mutations_total) / seconds;
  line.finish();

  const ExrImage img = exr_image_from_welch(welch);
  write_exr(a.out, img);
  const std::string png = std::filesystem::path(a.out).replace_extension(".png").string();
  std::vector<Rgb> mean(welch.pixels());
  for (size_t i = 0; i < mean.size(); ++i) mean[i] = welch.mean(i);
  write_png_preview(png, film.width(), film.height(), mean, 0.0);
  const std::string tiles_path = std::filesystem::path(a.out).replace_extension(".tiles.json").string();
  write_file_atomic(tiles_path, tiles.to_json());
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
                        {"nonfinite_samples", nonfinite},
                        {"mpi_ranks", mw.size},
                        {"pass_tiles", tiles_path},
                        // MCMC: one chain's splats spread over the image; pf1, pfk: a kernel reuses its
                        // neighbours' directions. Pixels of a pass are dependent, and tb compare decides on
                        // the pass-tile test (docs/integrator.md).
                        {"pixels_dependent_within_pass", !report.mutations.empty() || ramlt || a.integrator == "pf1" || a.integrator == "pfk"},
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
             static_cast<double>(spp_done) * static_cast<double>(film.pixel_count()) / seconds, nonfinite);
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
  if (a.integrator == "pf1" || a.integrator == "pfk") {
    const Pf1Timing t = pf1_last_timing();
    if (t.passes > 0)
      fmt::print("{}: {:.3f} s per pass in the prefix pass, {:.3f} s per pass filtering (kernels, weights, suffixes); "
                 "mean kernel {:.2f} prefixes\n",
                 a.integrator, t.prefix_seconds / double(t.passes), t.filter_seconds / double(t.passes), t.mean_members);
  }
  if (film.nonfinite().count() > 0)
    fmt::print("{} (replay: tb render {} --integrator {} --seed {})\n", film.nonfinite().summary(), a.scene,
               a.integrator, a.seed);
  if (nonfinite > film.nonfinite().count())
    fmt::print("{} more non-finite samples rejected on the other ranks\n", nonfinite - film.nonfinite().count());
  if (distributed) fmt::print("{} ranks under mpirun\n", mw.size);
  return 0;
}

}  // namespace tb

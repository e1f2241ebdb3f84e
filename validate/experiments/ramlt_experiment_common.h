// Shared machinery of the regional adaptive MLT experiments (`tb reproduce ramlt-fig10`,
// `ramlt-fig6`, `ramlt-target-acceptance`; docs/ramlt.md): the scene at the experiment's
// resolution with its BDPT reference (rendered once, cached on disk), and one measured point:
// `reps` independent run_ramlt replicates at one mutation budget, their rRMSE (root mean square
// of the replicates' luminance rRMSE), mean wall time and the perturbation's acceptance overall
// and per region.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/spectrum.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "validate/render/render_compare.h"

namespace tb::ramlt_exp {

struct SceneSetup {
  std::string file;
  std::unique_ptr<World> world;
  int res = 0, max_depth = 0;
  std::vector<Rgb> ref;
  bool ref_from_cache = false;
  std::string ref_path;
};

// Directory of the reference cache: $TB_REFERENCE_CACHE, else reports/cache (relative to the
// working directory, as `tb reproduce`'s default reports/out).
inline std::filesystem::path reference_cache_dir() {
  const char* env = std::getenv("TB_REFERENCE_CACHE");
  return env && *env ? std::filesystem::path(env) : std::filesystem::path("reports") / "cache";
}

// The scene `file` at res x res with max depth min(8, scene's) and its BDPT reference of `ref_spp`
// spp in 16 passes, seed hash(seed, "ramlt-fig10.ref." + file): the reference of ramlt-fig10, so
// every experiment at the same size and seed shares it. Cached as raw doubles under a name holding
// the file, size, spp, depth, seed and a hash of the scene file's text (an edited scene misses the
// cache); a cache file of the wrong size is ignored and rewritten.
inline SceneSetup load_scene_with_reference(const std::string& file, int res, int64_t ref_spp, uint64_t seed) {
  SceneSetup s;
  s.file = file;
  s.res = res;
  s.world = load_scene_at_resolution(file, res, res);
  s.max_depth = std::min(8, s.world->integrator_defaults().value("max_depth", 8));
  std::ifstream in_text(std::filesystem::path(scenes_dir()) / file, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in_text)), std::istreambuf_iterator<char>());
  const uint64_t ref_seed = hash_values(seed, hash_string("ramlt-fig10.ref." + file));
  const std::filesystem::path dir = reference_cache_dir();
  const std::filesystem::path path =
      dir / fmt::format("bdpt_{}_{}x{}_spp{}_d{}_seed{:016x}_scene{:016x}.f64",
                        std::filesystem::path(file).stem().string(), res, res, ref_spp, s.max_depth, ref_seed,
                        hash_string(text));
  s.ref_path = path.string();
  const size_t n = static_cast<size_t>(res) * static_cast<size_t>(res);
  {
    std::ifstream in(path, std::ios::binary);
    if (in) {
      std::vector<double> v(3 * n);
      in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(double)));
      const bool whole = in.gcount() == static_cast<std::streamsize>(v.size() * sizeof(double)) &&
                         in.peek() == std::char_traits<char>::eof();
      if (whole && std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); })) {
        s.ref.resize(n);
        for (size_t i = 0; i < n; ++i) s.ref[i] = Rgb(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        s.ref_from_cache = true;
        return s;
      }
    }
  }
  Film ref(res, res);
  RenderSettings rs;
  rs.spp = ref_spp;
  rs.passes = 16;
  rs.max_depth = s.max_depth;
  rs.seed = ref_seed;
  render_bdpt(*s.world, rs, ref);
  s.ref = ref.mean_image();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  std::vector<double> v(3 * n);
  for (size_t i = 0; i < n; ++i) v[3 * i] = s.ref[i].r, v[3 * i + 1] = s.ref[i].g, v[3 * i + 2] = s.ref[i].b;
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(double)));
  }
  std::filesystem::rename(tmp, path, ec);  // a cache that cannot be written is not an error
  return s;
}

struct Point {
  double rrmse = 0.0;          // sqrt(mean over replicates of rRMSE^2)
  double seconds = 0.0;        // mean wall time of a replicate
  double acceptance = 0.0;     // the perturbation's acceptance (last replicate)
  // Per region with >= 100 reports (last replicate): the median of the mean acceptance and the
  // fraction of regions whose mean acceptance is within 0.1 of a*.
  double region_acceptance_median = 0.0, region_within_01 = 0.0;
  int regions = 0, regions2 = 0, regions_reported = 0;
  int64_t mutations = 0;       // per replicate
  std::vector<double> replicate_rrmse;
  bool finite = true;
  double mutations_per_second() const { return static_cast<double>(mutations) / seconds; }
  // Median of the replicates' rRMSE (robust to the single heavy-tailed replicates of glossy scenes).
  double median_rrmse() const {
    std::vector<double> v = replicate_rrmse;
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  }
};

// `reps` replicates of run_ramlt with options `o` on the scene: `chains` chains (passes), `mpp`
// mutations per pixel; replicate r's seed is seed_of(r).
inline Point measure(const SceneSetup& sc, const path_space::RamltOptions& o, int64_t chains, int64_t mpp, int reps,
                     const std::function<uint64_t(int)>& seed_of) {
  Point p;
  double e2 = 0.0;
  path_space::RamltStats r;
  for (int rep_i = 0; rep_i < reps; ++rep_i) {
    RenderSettings st;
    st.passes = chains;
    st.spp = mpp;
    st.max_depth = sc.max_depth;
    st.seed = seed_of(rep_i);
    Film film(sc.res, sc.res);
    r = path_space::run_ramlt(*sc.world, st, film, o);
    const double ei = luminance_rrmse(film.mean_image(), sc.ref);
    p.finite = p.finite && std::isfinite(ei);
    p.replicate_rrmse.push_back(ei);
    e2 += ei * ei / reps;
    p.seconds += std::max(1e-6, r.mlt.seconds) / reps;
  }
  p.mutations = mpp * sc.res * sc.res;
  p.rrmse = std::sqrt(e2);
  p.finite = p.finite && std::isfinite(p.rrmse) && p.rrmse > 0.0;
  for (const auto& m : r.mlt.mutations)
    if (m.name.rfind("ramlt", 0) == 0) p.acceptance = m.acceptance_rate();
  p.regions = r.maps.regions;
  p.regions2 = r.maps.regions2;
  std::vector<double> acc;
  int within = 0;
  for (int k = 0; k < r.maps.regions; ++k)
    if (r.maps.visits[k] >= 100) {
      const double a = r.maps.acceptance_sum[k] / static_cast<double>(r.maps.visits[k]);
      acc.push_back(a);
      within += std::abs(a - o.adaptation.target_acceptance) <= 0.1;
    }
  p.regions_reported = static_cast<int>(acc.size());
  if (!acc.empty()) {
    std::nth_element(acc.begin(), acc.begin() + acc.size() / 2, acc.end());
    p.region_acceptance_median = acc[acc.size() / 2];
    p.region_within_01 = static_cast<double>(within) / static_cast<double>(acc.size());
  }
  return p;
}

}  // namespace tb::ramlt_exp

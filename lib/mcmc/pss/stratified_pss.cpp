#include "lib/mcmc/pss/stratified_pss.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/differential/variance_bound.h"
#include "lib/mcmc/stratified_target.h"
#include "lib/path/light_sampler.h"

namespace tb::pss {

namespace {
constexpr uint64_t kPilotKey = hash_string("stratified.pilot");
constexpr int64_t kPilotChunks = 64;  // fixed chunks: sums independent of the thread count
}  // namespace

double StratifiedTarget::ratio(const Splat& s) const {
  if (s.ratio > 0.0) return s.ratio;
  if (s.path.camera == nullptr) return 1.0;
  return differential::subpath_variance_ratio(*world_, *s.path.camera, s.path.t, s.path.s, mis_reduction_);
}

double StratifiedTarget::operator()(const std::vector<Splat>& splats) const {
  double pi = 0.0;
  for (const Splat& s : splats) {
    const double y = luminance(s.value);
    if (!(y > 0.0)) continue;  // zero (or invalid: the driver counts non-finite sums) splats add nothing
    pi += mcmc::stratified_target(y, 1.0, ratio(s), B_);  // Eq. 8: min{p r~, f / B}, p = 1 in PSS
  }
  return pi;
}

double pilot_brightness(const SampleFunction& f, int64_t n, uint64_t seed, double sigma) {
  const int levels = std::max(1, f.levels);
  n = std::max<int64_t>(levels, n);
  std::vector<double> sum(static_cast<size_t>(kPilotChunks), 0.0);
  parallel_for(static_cast<size_t>(kPilotChunks), [&](size_t chunk) {
    std::vector<Splat> sp;
    const int64_t lo = n * static_cast<int64_t>(chunk) / kPilotChunks, hi = n * static_cast<int64_t>(chunk + 1) / kPilotChunks;
    double acc = 0.0;
    for (int64_t i = lo; i < hi; ++i) {
      PssState s(Rng::for_sample(seed, kPilotKey, static_cast<uint64_t>(i)), sigma);
      sp.clear();
      s.restart();
      f.sample(static_cast<int>(i % levels), s, &sp);
      const double y = target_value(sp);
      if (std::isfinite(y) && y > 0.0) acc += y;
    }
    sum[chunk] = acc;
  });
  double total = 0.0;
  for (double v : sum) total += v;
  // Level l holds n / levels of the states: B = sum_l mean_l = levels * (sum of all) / n.
  return total * static_cast<double>(levels) / static_cast<double>(n);
}

int64_t run_stratified(const SampleFunction& f, const World& world, const RenderSettings& st, const PssSettings& pss,
                       const StratifiedSettings& ss, Film& film, StratifiedStats* stats) {
  StratifiedStats out;
  double B = ss.brightness;
  if (!(B > 0.0)) {
    const int64_t passes = std::max<int64_t>(1, st.passes);
    const int64_t N = pss.mutations_per_pass > 0 ? pss.mutations_per_pass
                                                  : std::max<int64_t>(1, st.spp / passes) * film.pixel_count();
    out.pilot_samples = ss.pilot > 0 ? ss.pilot : pss.bootstrap_for(N, f.levels);
    B = pilot_brightness(f, out.pilot_samples, st.seed, pss.sigma);
  }
  out.brightness = B;
  PssSettings p = pss;
  if (B > 0.0 && std::isfinite(B)) {
    const StratifiedTarget target(world, B, ss.mis_reduction);
    p.target = [target](const std::vector<Splat>& s) { return target(s); };
  }  // else: nothing was found; the plain target (the run finds nothing either, or little)
  const int64_t done = run_pss(f, st, p, film, &out.pss);
  if (pss.print_stats) fmt::print(stderr, "stratified: B = {:.6g} from {} pilot states\n", B, out.pilot_samples);
  if (stats) *stats = std::move(out);
  return done;
}

}  // namespace tb::pss

namespace tb {

int64_t render_mmlt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                               const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::mmlt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
  return pss::run_stratified(f, world, settings, p, ss, film, stats);
}

int64_t render_pssmlt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                                 const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::bdpt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
  return pss::run_stratified(f, world, settings, p, ss, film, stats);
}

int64_t render_pssmlt_pt_stratified(const World& world, const RenderSettings& settings, const pss::PssSettings& p,
                                    const pss::StratifiedSettings& ss, Film& film, pss::StratifiedStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::pt_paths_sample_function(ctx, settings, film.width(), film.height());
  return pss::run_stratified(f, world, settings, p, ss, film, stats);
}

namespace {

using StratifiedFn = int64_t (*)(const World&, const RenderSettings&, const pss::PssSettings&,
                                 const pss::StratifiedSettings&, Film&, pss::StratifiedStats*);

int64_t render_registered(StratifiedFn fn, const World& world, const RenderSettings& settings, Film& film,
                          bool rescaled = false) {
  pss::PssSettings p;
  p.rescale.enabled = rescaled;
  pss::StratifiedSettings ss;
  std::map<std::string, double> params = settings.params;
  if (auto it = params.find("mis_reduction"); it != params.end()) {
    if (it->second != 0 && it->second != 1)
      throw std::invalid_argument(fmt::format("parameter mis_reduction = {} must be 0 or 1", it->second));
    ss.mis_reduction = it->second == 1;
    params.erase(it);
  }
  pss::apply_params(params, &p);
  pss::StratifiedStats stats;
  const int64_t passes = fn(world, settings, p, ss, film, &stats);
  pss::fill_report(stats.pss, settings.report);
  return passes;
}

}  // namespace

int64_t render_mmlt_stratified(const World& world, const RenderSettings& settings, Film& film) {
  return render_registered(static_cast<StratifiedFn>(render_mmlt_stratified), world, settings, film);
}

int64_t render_pssmlt_stratified(const World& world, const RenderSettings& settings, Film& film) {
  return render_registered(static_cast<StratifiedFn>(render_pssmlt_stratified), world, settings, film);
}

int64_t render_pssmlt_pt_stratified(const World& world, const RenderSettings& settings, Film& film) {
  return render_registered(static_cast<StratifiedFn>(render_pssmlt_pt_stratified), world, settings, film);
}

int64_t render_pssmlt_pt_rescaled_stratified(const World& world, const RenderSettings& settings, Film& film) {
  return render_registered(static_cast<StratifiedFn>(render_pssmlt_pt_stratified), world, settings, film, true);
}

}  // namespace tb

#include "lib/mcmc/path_space/mlt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/parallel.h"
#include "lib/integrator/bdpt.h"
#include "lib/integrator/pass_loop.h"
#include "lib/mcmc/path_space/mlt_chain.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/dirac.h"

namespace tb::path_space {


MltStats run_mlt(const World& world, const RenderSettings& st, Film& film, const MltOptions& opt) {
  const Camera& cam = world.camera();
  if (!cam.lens_is_delta()) throw std::invalid_argument("mlt: path-space MLT needs a pinhole camera");
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const int max_depth = std::max(0, st.max_depth);
  const PathTarget target{&ctx};
  PathMutationSettings ms;
  ms.max_segments = max_depth + 1;
  const PathMixture mixture(opt.mutations ? opt.mutations(ctx, ms) : make_path_mutations(ctx, ms));
  const size_t K = static_cast<size_t>(mixture.components());

  const int64_t P = cam.pixel_count();
  const int64_t chains = std::max<int64_t>(1, st.passes);
  const int64_t M = std::max<int64_t>(1, st.spp * P / chains);
  const int64_t n_boot = opt.bootstrap_per_chain > 0 ? opt.bootstrap_per_chain : std::max<int64_t>(256, 4 * P / chains);
  // A target other than Y(f) (MltTarget), with its default start-up term w_{s,t} pi / p_{s,t}.
  MltTarget tgt = opt.target ? opt.target(ctx, st) : MltTarget{};
  const bool custom = static_cast<bool>(tgt.density);
  if (custom && !tgt.startup)
    tgt.startup = [&ctx, &tgt](const Connection& c, const MltPath& x) {
      // f of the chain's convention without shadow rays: BDPT's segments are visible by
      // construction (its connection tested), and c.value > 0 here.
      const Rgb f = measurement_contribution(ctx, x.v, false, DiracPolicy::kCoefficient);
      const double y = luminance(f);
      return y > 0.0 ? luminance(c.value) * tgt.density(x, f) / y : 0.0;
    };

  MltStats stats;
  stats.brightness = tgt.brightness;
  stats.pilot_samples = tgt.pilot_samples;
  for (int k = 0; k < mixture.components(); ++k) stats.mutations.push_back(MutationStats{mixture.name(k)});
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t batch = 16;  // chains per parallel batch: bounds splat memory, independent of threads
  double b_sum = 0.0;
  for_each_pass_batch(st, chains, batch, [&](int64_t first, int64_t count) {
    std::vector<SplatBuffer> splats(static_cast<size_t>(count), SplatBuffer(film.width(), film.height()));
    std::vector<double> b(static_cast<size_t>(count), 0.0);
    std::vector<std::vector<mcmc::ComponentCounts>> local(static_cast<size_t>(count),
                                                          std::vector<mcmc::ComponentCounts>(K));
    std::vector<int64_t> done(static_cast<size_t>(count), 0);
    std::vector<double> startup_s(static_cast<size_t>(count), 0.0);
    parallel_for(static_cast<size_t>(count), [&](size_t ci) {
      const uint64_t chain = static_cast<uint64_t>(first) + ci;
      const auto c0 = std::chrono::steady_clock::now();
      // Start-up: bootstrap estimate of b and resampling of the start path by Y(contribution).
      Rng stream = Rng::for_sample(st.seed, 0x6d6c7401ULL, chain);
      RngUniforms u(stream);
      ChainStart start = custom ? start_chain(ctx, st.seed, chain, n_boot, max_depth, u.next(), tgt.startup)
                                : start_chain(ctx, st.seed, chain, n_boot, max_depth, u.next());
      b[ci] = start.b;
      startup_s[ci] = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
      if (!start.x) return;
      MltChain c;
      c.mix = &mixture;
      c.target = &target;
      if (custom) c.density = &tgt.density;
      c.x = std::move(*start.x);
      c.fx = target.contribution(c.x);
      c.pix = c.score(c.x, c.fx);
      c.start();
      auto& ls = local[ci];
      for (int64_t j = 0; j < M; ++j) {
        const uint64_t index = static_cast<uint64_t>(j);
        // Expected values (Veach 1997, Sec. 11.5): x with 1 - a, y with a, each splat f / Y(f).
        const mcmc::StepOutcome o = mcmc::chain_step(c, u, u, [&](mcmc::Which which, double w) {
          const bool cur = which == mcmc::Which::kCurrent;
          const double pi = cur ? c.pix : c.piy;
          if (!(pi > 0.0)) return;
          const MltPath& p = cur ? c.x : *c.y;
          const auto r = path_raster(ctx, p);
          if (!r) return;
          const Rgb& f = cur ? c.fx : c.fy;
          // f / pi; for the stratified target f / W~, of luminance S~ (Eq. 8, Sec. 6.1).
          const double d = tgt.splat_divisor ? tgt.splat_divisor(p, f, pi) : pi;
          if (d > 0.0) splats[ci].splat(*r, f * (w / d), index);
        });
        if (o.component >= 0) ls[static_cast<size_t>(o.component)].add(o);
      }
      done[ci] = M;
    });
    for (int64_t ci = 0; ci < count; ++ci) {
      film.merge_splats(splats[ci]);
      const double scale = static_cast<double>(P) * b[ci] / static_cast<double>(M);
      film.end_pass(splats[ci].entries().empty() ? 0.0 : scale);
      b_sum += b[ci];
      stats.startup_seconds += startup_s[ci];
      if (done[ci] == 0) ++stats.chains_without_start;
      stats.mutations_total += done[ci];
      for (size_t k = 0; k < K; ++k) {
        stats.mutations[k].add(local[ci][k]);
      }
      ++stats.chains;
    }
  });
  stats.b_mean = stats.chains > 0 ? b_sum / static_cast<double>(stats.chains) : 0.0;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace tb::path_space

namespace tb {

namespace path_space {
void fill_report(const MltStats& stats, RunReport* report) {
  if (!report) return;
  report->mutations.clear();
  for (const auto& m : stats.mutations) report->mutations.push_back({m.name, m.proposed, m.accepted, m.errors});
  report->mutations_total = stats.mutations_total;
  report->mutations_per_second = stats.mutations_per_second();
  report->startup_seconds = stats.startup_seconds;
}
}  // namespace path_space

int64_t render_mlt(const World& world, const RenderSettings& settings, Film& film) {
  const path_space::MltStats stats = path_space::run_mlt(world, settings, film);
  path_space::fill_report(stats, settings.report);
  return stats.chains;
}

}  // namespace tb

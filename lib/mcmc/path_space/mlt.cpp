#include "lib/mcmc/path_space/mlt.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/proposal_mixture.h"
#include "lib/core/parallel.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/start_paths.h"

namespace tb::path_space {

MltStats run_mlt(const World& world, const RenderSettings& st, Film& film, const MltOptions& opt) {
  const Camera& cam = world.camera();
  if (!cam.lens_is_delta()) throw std::invalid_argument("mlt: path-space MLT needs a pinhole camera");
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const int max_depth = std::max(0, st.max_depth);
  const int max_segments = max_depth + 1;
  const PathTarget target{&ctx};
  const BidirectionalMutation bidir(ctx, max_segments, opt.bidir_fault);
  const LensPerturbation lens(ctx, 0.1, 0.0, opt.lens_fault);
  const CausticPerturbation caustic(ctx);
  const MultiChainPerturbation multi(ctx);
  const mcmc::Mixture mixture(opt.selection, bidir, lens, caustic, multi);
  constexpr int kComponents = 4;

  const int64_t P = cam.pixel_count();
  const int64_t chains = std::max<int64_t>(1, st.passes);
  const int64_t M = std::max<int64_t>(1, st.spp * P / chains);
  const int64_t n_boot = opt.bootstrap_per_chain > 0 ? opt.bootstrap_per_chain : std::max<int64_t>(256, 4 * P / chains);

  MltStats stats;
  stats.mutations = {MutationStats{"bidirectional"}, MutationStats{"lens"}, MutationStats{"caustic"},
                     MutationStats{"multi-chain"}};
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t batch = 16;  // chains per parallel batch: bounds splat memory, independent of threads
  double b_sum = 0.0;
  for (int64_t first = 0; first < chains; first += batch) {
    if (st.interrupted && st.interrupted->load()) break;
    const int64_t count = std::min(batch, chains - first);
    std::vector<SplatBuffer> splats(static_cast<size_t>(count), SplatBuffer(film.width(), film.height()));
    std::vector<double> b(static_cast<size_t>(count), 0.0);
    std::vector<std::array<MutationStats, kComponents>> local(static_cast<size_t>(count));
    std::vector<int64_t> done(static_cast<size_t>(count), 0);
    parallel_for(static_cast<size_t>(count), [&](size_t ci) {
      const uint64_t chain = static_cast<uint64_t>(first) + ci;
      // Start-up: bootstrap estimate of b and resampling of the start path by Y(contribution).
      Rng stream = Rng::for_sample(st.seed, 0x6d6c7401ULL, chain);
      RngUniforms u(stream);
      ChainStart start = start_chain(ctx, st.seed, chain, n_boot, max_depth, u.next());
      b[ci] = start.b;
      if (!start.x) return;
      MltPath x = std::move(*start.x);
      Rgb fx = target.contribution(x);
      double pix = std::max(0.0, luminance(fx));
      auto splat = [&](const MltPath& p, const Rgb& f, double pi, double weight, uint64_t index) {
        if (!(weight > 0.0) || !(pi > 0.0)) return;
        const auto r = path_raster(ctx, p);
        if (r) splats[ci].splat(*r, f * (weight / pi), index);
      };
      auto& ls = local[ci];
      for (int64_t j = 0; j < M; ++j) {
        const int comp = std::max(0, mcmc::select_component(mixture, x, u.next()));
        auto y = mixture.propose(comp, x, u);
        const double ua = u.next();
        ++ls[comp].proposed;
        if (!y) {
          ++ls[comp].failed;
          splat(x, fx, pix, 1.0, static_cast<uint64_t>(j));
          continue;
        }
        const Rgb fy = target.contribution(*y);
        const double piy = std::max(0.0, luminance(fy));
        double a = 0.0;
        if (piy > 0.0) {  // the estimators' rule with the mutation's own densities
          const double fwd = mixture.selection(comp, x) * mixture.density(comp, x, *y);
          const double rev = mixture.selection(comp, *y) * mixture.density(comp, *y, x);
          a = mcmc::HastingsRatio{}(pix, fwd, piy, rev);
        }
        ls[comp].acceptance_sum += a;
        splat(x, fx, pix, 1.0 - a, static_cast<uint64_t>(j));  // expected values (Veach 1997, Sec. 11.5)
        splat(*y, fy, piy, a, static_cast<uint64_t>(j));
        if (ua < a) {
          ++ls[comp].accepted;
          x = std::move(*y);
          fx = fy;
          pix = piy;
        }
      }
      done[ci] = M;
    });
    for (int64_t ci = 0; ci < count; ++ci) {
      film.merge_splats(splats[ci]);
      const double scale = static_cast<double>(P) * b[ci] / static_cast<double>(M);
      film.end_pass(splats[ci].entries().empty() ? 0.0 : scale);
      b_sum += b[ci];
      if (done[ci] == 0) ++stats.chains_without_start;
      stats.mutations_total += done[ci];
      for (int j = 0; j < kComponents; ++j) {
        stats.mutations[j].proposed += local[ci][j].proposed;
        stats.mutations[j].failed += local[ci][j].failed;
        stats.mutations[j].accepted += local[ci][j].accepted;
        stats.mutations[j].acceptance_sum += local[ci][j].acceptance_sum;
      }
      ++stats.chains;
    }
    st.progress(static_cast<double>(stats.chains) / static_cast<double>(chains));
    if (st.time_budget_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > st.time_budget_s)
      break;
  }
  stats.b_mean = stats.chains > 0 ? b_sum / static_cast<double>(stats.chains) : 0.0;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace tb::path_space

namespace tb {

int64_t render_mlt(const World& world, const RenderSettings& settings, Film& film) {
  const path_space::MltStats stats = path_space::run_mlt(world, settings, film);
  if (settings.report) {
    settings.report->mutations.clear();
    for (const auto& m : stats.mutations) settings.report->mutations.push_back({m.name, m.proposed, m.accepted});
    settings.report->mutations_total = stats.mutations_total;
    settings.report->mutations_per_second = stats.mutations_per_second();
  }
  return stats.chains;
}

}  // namespace tb

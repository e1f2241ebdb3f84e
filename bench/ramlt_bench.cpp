// Regional adaptive MLT throughput (docs/ramlt.md, "Speed"), on the Cornell box at 64 x 64, max
// depth 5:
//  - BM_RamltLensMixture / BM_VeachLensMixture: mutations/s of run_ramlt (bidirectional + ramlt-lens
//    0.5 / 0.5, 20 x 20 grid, adapting) and of run_mlt with Veach's lens perturbation in the same
//    0.5 / 0.5 mixture with the bidirectional mutation; 16 chains x 8192 mutations, 2 threads
//    (counter mutations/s: the drivers' own figure, start-up included for both);
//  - BM_RamltProposal: one ramlt-lens proposal with what the chain step does with it (propose,
//    f(y), T(x -> y), T(y -> x)) from 1024 fixed Cornell paths, 1 thread: the cost of a mutation
//    without splatting;
//  - BM_RamltBookkeeping: what the adaptation adds per proposal in the driver: the region of x,
//    the recorded (region, a), and Algorithm 1's observe() (Otsu Eq. 4-6), 1 thread.
// Report: BookkeepingTime / ProposalTime (target < 10%).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include "estimators/mcmc/adaptation.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {
namespace {

constexpr int kRes = 64;
constexpr int kDepth = 5;

struct Box {
  Box() {
    setenv("TB_SCENES_DIR", TB_SOURCE_DIR "/scenes", 0);
    world = load_scene_at_resolution("cornell-box.json", kRes, kRes);
    lights = std::make_unique<LightSampler>(*world);
    ctx = PathContext{world.get(), lights.get()};
  }
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
};
Box& box() {
  static Box b;
  return b;
}

RenderSettings settings() {
  RenderSettings st;
  st.passes = 16;
  st.spp = 16 * 8192 / (kRes * kRes);
  st.max_depth = kDepth;
  st.seed = 3;
  return st;
}

void BM_RamltLensMixture(benchmark::State& state) {
  const ThreadLimit limit(2);
  double mutations = 0.0, seconds = 0.0;
  for (auto _ : state) {
    Film film(kRes, kRes);
    const RamltStats s = run_ramlt(*box().world, settings(), film);
    mutations += static_cast<double>(s.mlt.mutations_total);
    seconds += s.mlt.seconds;
    state.counters["adaptation_share"] = s.adaptation_seconds / s.mlt.seconds;
  }
  state.counters["mutations/s"] = seconds > 0 ? mutations / seconds : 0.0;
}
BENCHMARK(BM_RamltLensMixture)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_VeachLensMixture(benchmark::State& state) {
  const ThreadLimit limit(2);
  MltOptions o;
  o.mutations = [](const PathContext& ctx, const PathMutationSettings& ms) {
    return PathMutationList{
        std::make_shared<const PathProposalMutation<BidirectionalMutation>>("bidirectional", 0.5,
                                                                            BidirectionalMutation(ctx, ms.max_segments)),
        std::make_shared<const PathProposalMutation<LensPerturbation>>(
            "lens", 0.5, LensPerturbation(ctx), [](const LensPerturbation& l, const MltPath& x) { return l.applicable(x); })};
  };
  double mutations = 0.0, seconds = 0.0;
  for (auto _ : state) {
    Film film(kRes, kRes);
    const MltStats s = run_mlt(*box().world, settings(), film, o);
    mutations += static_cast<double>(s.mutations_total);
    seconds += s.seconds;
  }
  state.counters["mutations/s"] = seconds > 0 ? mutations / seconds : 0.0;
}
BENCHMARK(BM_VeachLensMixture)->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(2.0);

// 1024 Cornell paths the lens perturbation applies to, and a grid at lambda = -6 (sigma 0.05 rad).
struct Fixture {
  Fixture() : scale(RegionalScale::uniform(ScreenPartition::make(box().ctx, "grid", 20), -6.0)), lens(box().ctx, scale) {
    Rng rng = Rng::for_sample(5, 0, 0);
    RngUniforms u(rng);
    while (paths.size() < 1024)
      if (auto x = sample_bdpt_path(box().ctx, u, kDepth))
        if (lens.applicable(*x)) paths.push_back(*x);
  }
  RegionalScale scale;
  RamltLensPerturbation lens;
  std::vector<MltPath> paths;
};
Fixture& fixture() {
  static Fixture f;
  return f;
}

void BM_RamltProposal(benchmark::State& state) {
  Fixture& f = fixture();
  const PathTarget target{&box().ctx};
  Rng rng = Rng::for_sample(9, 0, 0);
  RngUniforms u(rng);
  size_t i = 0;
  double sink = 0.0;
  for (auto _ : state) {
    const MltPath& x = f.paths[i++ & 1023];
    if (auto y = f.lens.propose(x, u)) {
      sink += luminance(target.contribution(*y)) + f.lens.density(x, *y) + f.lens.density(*y, x);
    }
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RamltProposal);

void BM_RamltBookkeeping(benchmark::State& state) {
  Fixture& f = fixture();
  mcmc::OtsuAdaptation adapter(f.scale.partition->regions(), {});
  std::vector<std::pair<int, double>> obs;
  obs.reserve(4096);
  size_t i = 0;
  for (auto _ : state) {
    const MltPath& x = f.paths[i & 1023];
    obs.emplace_back(f.scale.region(x), 0.25 + 0.5 * static_cast<double>(i & 1));
    if (obs.size() == 4096) {  // applied in batches, as the driver does
      for (const auto& [r, a] : obs) adapter.observe(r, a);
      obs.clear();
    }
    ++i;
  }
  benchmark::DoNotOptimize(adapter.lambda(0));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RamltBookkeeping);

}  // namespace
}  // namespace tb::path_space

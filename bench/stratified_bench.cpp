// The cost of the stratified target of Zirr & Dachsbacher 2020 (lib/mcmc/pss/stratified_pss.h:
// pi = sum over splats of min{r~, Y(v) / B}, r~ from Eq. 21 on the splat's camera subpath) against
// the plain target Y(sum v), on the same primary-sample states: the sample function (MMLT's one
// technique per state; BDPT's all connections) followed by the target, over 4096 fixed uniform
// states of the Cornell box and the glossy scene at 64 x 64. The difference is the overhead per
// state evaluation that a chain pays (Sec. 8 of the paper: about 25% fewer mutations for
// stratified Veach MLT, about 5% for its forward sampler). Run interleaved, so that machine drift
// hits both alike:
//   ./build/bench/stratified_bench --benchmark_enable_random_interleaving=true --benchmark_repetitions=6
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lib/core/rng.h"
#include "lib/mcmc/pss/pss_sample.h"
#include "lib/mcmc/pss/pss_state.h"
#include "lib/mcmc/pss/stratified_pss.h"
#include "lib/path/light_sampler.h"
#include "validate/render/render_compare.h"

namespace {

using namespace tb;

struct Setup {
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> sampler;
  PathContext ctx;
  pss::SampleFunction f;
  double B = 0.0;
};

const Setup& setup(const std::string& scene, bool mmlt) {
  static std::map<std::pair<std::string, bool>, std::unique_ptr<Setup>> cache;
  auto& s = cache[{scene, mmlt}];
  if (!s) {
    s = std::make_unique<Setup>();
    s->world = load_scene_at_resolution(scene, 64, 64);
    s->sampler = std::make_unique<LightSampler>(*s->world);
    s->ctx = PathContext{s->world.get(), s->sampler.get()};
    s->f = mmlt ? pss::mmlt_sample_function(s->ctx, 64, 64, 5) : pss::bdpt_sample_function(s->ctx, 64, 64, 5);
    s->B = pss::pilot_brightness(s->f, 16384, 7, 0.01);
  }
  return *s;
}

// The measured loop, a function of its own so that instruction counts can be restricted to it:
//   valgrind --tool=callgrind --toggle-collect='*state_loop*' ./build/bench/stratified_bench
//     --benchmark_filter='BM_MmltPlain/cornell$' --benchmark_min_time=0.000001   (one line)
template <bool kStratified>
[[gnu::noinline]] double state_loop(const Setup& s, const pss::StratifiedTarget& target, std::vector<pss::Splat>& sp) {
  double sum = 0.0;
  for (uint64_t i = 0; i < 4096; ++i) {
    pss::PssState st(Rng::for_sample(3, 5, i), 0.01);
    st.restart();
    sp.clear();
    s.f.sample(static_cast<int>(i % static_cast<uint64_t>(s.f.levels)), st, &sp);
    sum += kStratified ? target(sp) : pss::target_value(sp);
  }
  return sum;
}

template <bool kStratified>
void evaluate(benchmark::State& state, const std::string& scene, bool mmlt) {
  const Setup& s = setup(scene, mmlt);
  const pss::StratifiedTarget target(*s.world, s.B, true);
  std::vector<pss::Splat> sp;
  double sum = 0.0;
  for (auto _ : state) sum += state_loop<kStratified>(s, target, sp);
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * 4096);
}

void BM_MmltPlain(benchmark::State& st, std::string scene) { evaluate<false>(st, scene, true); }
void BM_MmltStratified(benchmark::State& st, std::string scene) { evaluate<true>(st, scene, true); }
void BM_BdptPlain(benchmark::State& st, std::string scene) { evaluate<false>(st, scene, false); }
void BM_BdptStratified(benchmark::State& st, std::string scene) { evaluate<true>(st, scene, false); }

BENCHMARK_CAPTURE(BM_MmltPlain, cornell, std::string("cornell-box.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MmltStratified, cornell, std::string("cornell-box.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BdptPlain, cornell, std::string("cornell-box.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BdptStratified, cornell, std::string("cornell-box.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MmltPlain, glossy, std::string("glossy.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MmltStratified, glossy, std::string("glossy.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BdptPlain, glossy, std::string("glossy.json"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BdptStratified, glossy, std::string("glossy.json"))->Unit(benchmark::kMillisecond);

}  // namespace

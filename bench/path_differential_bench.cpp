// Path differentials (Zirr & Dachsbacher 2020, App. B.2): the endpoint covariance of Eq. 18 by the
// O(k) incremental form against the O(k^2) recurrence (Eq. 44 once per random variable u_i), over
// the path length k. Blocks are synthetic (random 2x2 with spectral radius < 1) so that k can go
// far beyond a rendered path; the real per-path cost (trace, differentiate, covariance) is
// measured on cornell-box for k = 2..8. After the runs the least-squares slopes of log(time)
// against log(k) (CPU time) are printed (expected: 1 and 2).
//   ./build/bench/path_differential_bench   (scenes from $TB_SCENES_DIR or found upwards, see scenes_dir())
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lib/core/rng.h"
#include "lib/differential/path_differential.h"
#include "lib/scene/scene_loader.h"
#include "validate/render/render_compare.h"

namespace {

using namespace tb;
using namespace tb::differential;

std::vector<StepBlocks> synthetic_blocks(int k) {
  Rng rng = Rng::for_sample(1, 2, static_cast<uint64_t>(k));
  const auto random2 = [&](double scale) {
    Mat2 m = Mat2::Zero();
    for (int i = 0; i < 4; ++i) m(i / 2, i % 2) = (rng.uniform() - 0.5) * scale;
    return m;
  };
  std::vector<StepBlocks> b(static_cast<size_t>(k));
  b[0].g_u = random2(1.0);
  for (int j = 1; j < k; ++j) b[j] = {random2(0.4), random2(0.4), random2(1.0)};
  return b;
}

EndpointMap synthetic_map() {
  EndpointMap e;
  e.p_x = Mat2::Identity();
  e.d_prev = 0.5 * Mat2::Identity();
  e.d_cur = -0.5 * Mat2::Identity();
  return e;
}

void BM_Incremental(benchmark::State& state) {
  const auto blocks = synthetic_blocks(static_cast<int>(state.range(0)));
  const EndpointMap e = synthetic_map();
  for (auto _ : state) benchmark::DoNotOptimize(endpoint_covariance_incremental(blocks, e));
  state.SetComplexityN(state.range(0));
}

void BM_FullRecurrence(benchmark::State& state) {
  const auto blocks = synthetic_blocks(static_cast<int>(state.range(0)));
  const EndpointMap e = synthetic_map();
  for (auto _ : state) benchmark::DoNotOptimize(endpoint_covariance_full(blocks, e));
  state.SetComplexityN(state.range(0));
}

BENCHMARK(BM_Incremental)->RangeMultiplier(2)->Range(8, 512);
BENCHMARK(BM_FullRecurrence)->RangeMultiplier(2)->Range(8, 512);

// A rendered path: trace X(U), differentiate (blocks), covariance by the incremental form.
void BM_CornellPath(benchmark::State& state) {
  static const std::unique_ptr<World> world = load_world(scenes_dir() + "/cornell-box.json");
  const int k = static_cast<int>(state.range(0));
  const auto sp = sample_path(*world, k, 1, 3, 0);
  if (!sp) {
    state.SkipWithError("no path");
    return;
  }
  for (auto _ : state) {
    const auto p = trace_forward(*world, sp->pixel, sp->U, k, sp->lobe);
    const PathDifferential d = differentiate(*world, sp->pixel, *p, sp->U);
    benchmark::DoNotOptimize(endpoint_covariance_incremental(d.blocks, endpoint_map(*p, d)));
  }
}
BENCHMARK(BM_CornellPath)->DenseRange(2, 8, 2);

// Collects (k, time per iteration) per benchmark family for the slope fit.
class SlopeReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.iterations == 0) continue;
      const std::string name = r.benchmark_name();
      const size_t slash = name.find('/');
      if (slash == std::string::npos) continue;
      const double k = std::stod(name.substr(slash + 1));
      points_[name.substr(0, slash)].push_back({std::log(k), std::log(r.GetAdjustedCPUTime())});
    }
  }
  void PrintSlopes() const {
    for (const auto& [family, pts] : points_) {
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      for (const auto& [x, y] : pts) {
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
      }
      const double n = static_cast<double>(pts.size());
      const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
      std::printf("log-log slope of time over k, %s: %.3f (%zu points)\n", family.c_str(), slope, pts.size());
    }
  }

 private:
  std::map<std::string, std::vector<std::pair<double, double>>> points_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  SlopeReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.PrintSlopes();
  benchmark::Shutdown();
  return 0;
}

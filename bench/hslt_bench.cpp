// Determinant + one linear solve of the block-tridiagonal half-vector constraint Jacobian
// (Kaplanyan et al. 2014, Eq. 11): block LU (lib/differential/hslt_block_lu.h, Sec. 7) against
// dense Eigen PartialPivLU, for path lengths k = 2 .. 64 (k - 1 blocks of 2 x 2). The blocks are
// random and diagonally dominant (the cost does not depend on the values). Each iteration
// factors from the blocks, takes the determinant and solves one right-hand side; the dense
// variant includes assembling the 2(k-1) x 2(k-1) matrix.
// After the runs the least-squares slopes of log(time) against log(k - 1) are printed, over
// k = 8 .. 64 (smaller sizes are dominated by fixed overheads); expected about 1 (block LU) and
// about 3 (dense LU); and the slope between consecutive sizes (the dense LU of a 126 x 126
// matrix is only reaching its cubic regime at the top of the range).
// BM_HsltStep/k: one Metropolis step of the half-vector mutation (lib/mcmc/path_space/hslt_mutation.h)
// on the 16 x 16 glossy scene, from 64 fixed BDPT paths of k segments it applies to: propose (forward
// and reverse walk) and, for a proposal, T(x -> y) and T(y -> x) (two walks each), as the chain's
// acceptance evaluates them; not in the slope fit.
// Run: ./build/bench/hslt_bench
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "lib/core/rng.h"
#include "lib/differential/hslt_block_lu.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

HsltBlocks random_blocks(int n) {
  Rng rng = Rng::for_sample(1, 2, static_cast<uint64_t>(n));
  auto block = [&](double diag) {
    Eigen::Matrix2d m;
    m << 2 * rng.uniform() - 1 + diag, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1 + diag;
    return m;
  };
  HsltBlocks b;
  for (int r = 0; r < n; ++r) {
    b.A.push_back(block(0));
    b.B.push_back(block(3));
    b.C.push_back(block(0));
  }
  return b;
}

Eigen::VectorXd rhs_for(int n) { return Eigen::VectorXd::LinSpaced(2 * n, -1.0, 1.0); }

void BM_HsltBlockLu(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)) - 1;
  const HsltBlocks b = random_blocks(n);
  const Eigen::VectorXd rhs = rhs_for(n);
  for (auto _ : state) {
    const HsltBlockLu lu(b);
    benchmark::DoNotOptimize(lu.log_abs_determinant());
    Eigen::VectorXd x = lu.solve(rhs);
    benchmark::DoNotOptimize(x.data());
  }
}

void BM_HsltDenseLu(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0)) - 1;
  const HsltBlocks b = random_blocks(n);
  const Eigen::VectorXd rhs = rhs_for(n);
  for (auto _ : state) {
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(hslt_dense_jacobian(b));
    benchmark::DoNotOptimize(lu.determinant());
    Eigen::VectorXd x = lu.solve(rhs);
    benchmark::DoNotOptimize(x.data());
  }
}

struct GlossyPaths {
  std::unique_ptr<World> world = load_scene_at_resolution("glossy.json", 16, 16);
  LightSampler lights{*world};
  PathContext ctx{world.get(), &lights};
  std::map<int, std::vector<path_space::MltPath>> by_length;
  const std::vector<path_space::MltPath>& paths(int k) {
    auto& v = by_length[k];
    if (!v.empty()) return v;
    const path_space::HsltMutation m(ctx);
    Rng rng = Rng::for_sample(1, 3, static_cast<uint64_t>(k));
    RngUniforms u(rng);
    for (int a = 0; a < 400000 && v.size() < 64; ++a)
      if (auto p = path_space::sample_bdpt_path(ctx, u, k - 1, k))
        if (p->segments() == k && m.applicable(*p)) v.push_back(*p);
    return v;
  }
};

void BM_HsltStep(benchmark::State& state) {
  static GlossyPaths g;
  const int k = static_cast<int>(state.range(0));
  const auto& paths = g.paths(k);
  if (paths.empty()) {
    state.SkipWithError("no paths");
    return;
  }
  const path_space::HsltMutation m(g.ctx);
  Rng rng = Rng::for_sample(2, 3, static_cast<uint64_t>(k));
  RngUniforms u(rng);
  size_t i = 0;
  int64_t proposals = 0;
  for (auto _ : state) {
    const auto& x = paths[i++ % paths.size()];
    const auto y = m.propose(x, u);
    if (y) {
      ++proposals;
      benchmark::DoNotOptimize(m.density(x, *y));
      benchmark::DoNotOptimize(m.density(*y, x));
    }
  }
  state.counters["generated"] = benchmark::Counter(static_cast<double>(proposals) / static_cast<double>(state.iterations()));
}

BENCHMARK(BM_HsltBlockLu)->RangeMultiplier(2)->Range(2, 64);
BENCHMARK(BM_HsltDenseLu)->RangeMultiplier(2)->Range(2, 64);
BENCHMARK(BM_HsltStep)->Arg(2)->Arg(3)->Arg(4)->Unit(benchmark::kMicrosecond);

// Console output as usual, and the time per iteration of every run kept for the slope fit.
class SlopeReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, std::vector<std::pair<double, double>>> points;  // family -> (k - 1, ns)
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      const std::string name = r.benchmark_name();
      const auto slash = name.find('/');
      if (slash == std::string::npos || r.run_type != Run::RT_Iteration) continue;
      const double k = std::stod(name.substr(slash + 1));
      points[name.substr(0, slash)].emplace_back(k - 1, r.GetAdjustedRealTime());
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

double slope(const std::vector<std::pair<double, double>>& p, double min_n) {
  std::vector<double> x, y;
  for (auto [n, t] : p)
    if (n >= min_n) x.push_back(std::log(n)), y.push_back(std::log(t));
  const double m = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) mx += x[i] / m, my += y[i] / m;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

}  // namespace
}  // namespace tb

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  tb::SlopeReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  std::printf("\nlog-log slope of time against the number of blocks k - 1, over k = 8 .. 64:\n");
  for (const auto& [name, p] : reporter.points) {
    if (p.size() < 3 || name.find("Lu") == std::string::npos) continue;
    std::printf("  %-16s slope %.2f  (k = 2 .. 64: %.2f); per doubling:", name.c_str(), tb::slope(p, 7),
                tb::slope(p, 1));
    for (size_t i = 1; i < p.size(); ++i)
      std::printf(" %.2f", std::log(p[i].second / p[i - 1].second) / std::log(p[i].first / p[i - 1].first));
    std::printf("\n");
  }
  benchmark::Shutdown();
  return 0;
}

// Single-thread throughput of the random streams and the sampling warps of lib/core.
// Run: ./build/bench/core_bench  (items_per_second = samples/s).
#include <vector>

#include <benchmark/benchmark.h>

#include "lib/core/discrete.h"
#include "lib/core/rng.h"
#include "lib/core/truncated_normal.h"
#include "lib/core/warp_disk.h"
#include "lib/core/warp_sphere.h"
#include "lib/core/warp_triangle.h"

namespace tb {
namespace {

void BM_RngUniform(benchmark::State& state) {
  Rng rng(1);
  for (auto _ : state) benchmark::DoNotOptimize(rng.uniform());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RngUniform);

void BM_RngForSample(benchmark::State& state) {
  uint64_t i = 0;
  for (auto _ : state) {
    Rng r = Rng::for_sample(1, 2, i++);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RngForSample);

// Runs `f(u)` on fresh uniforms each iteration; the RNG cost (~ BM_RngUniform x 2) is included.
template <class F>
void run_warp(benchmark::State& state, F&& f) {
  Rng rng(7);
  for (auto _ : state) benchmark::DoNotOptimize(f(rng.uniform2()));
  state.SetItemsProcessed(state.iterations());
}

void BM_DiskConcentric(benchmark::State& s) { run_warp(s, sample_uniform_disk_concentric); }
void BM_DiskConcentricInverse(benchmark::State& s) {
  run_warp(s, [](Vec2 u) { return invert_uniform_disk_concentric(sample_uniform_disk_concentric(u)); });
}
void BM_DiskPdf(benchmark::State& s) { run_warp(s, [](Vec2 u) { return pdf_uniform_disk(u - 0.5); }); }
void BM_UniformSphere(benchmark::State& s) { run_warp(s, sample_uniform_sphere); }
void BM_UniformSpherePdf(benchmark::State& s) {
  run_warp(s, [](Vec2 u) { return pdf_uniform_sphere() + u.x; });
}
void BM_UniformHemisphere(benchmark::State& s) { run_warp(s, sample_uniform_hemisphere); }
void BM_UniformHemispherePdf(benchmark::State& s) {
  run_warp(s, [](Vec2 u) { return pdf_uniform_hemisphere({u.x, u.y, u.x - 0.2}); });
}
void BM_CosineHemisphere(benchmark::State& s) { run_warp(s, sample_cosine_hemisphere); }
void BM_CosineHemispherePdf(benchmark::State& s) {
  run_warp(s, [](Vec2 u) { return pdf_cosine_hemisphere({u.x, u.y, u.x - 0.2}); });
}
void BM_UniformCone(benchmark::State& s) { run_warp(s, [](Vec2 u) { return sample_uniform_cone(u, 0.7); }); }
void BM_UniformConePdf(benchmark::State& s) {
  run_warp(s, [](Vec2 u) { return pdf_uniform_cone({u.x, u.y, u.x}, 0.7); });
}
void BM_UniformTriangle(benchmark::State& s) {
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(0.3, 1, 0.2);
  run_warp(s, [&](Vec2 u) { return sample_uniform_triangle(p0, p1, p2, u); });
}
void BM_UniformTrianglePdf(benchmark::State& s) {
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(0.3, 1, 0.2);
  run_warp(s, [&](Vec2 u) { return pdf_uniform_triangle(p0, p1 + u.x, p2); });
}
BENCHMARK(BM_DiskConcentric);
BENCHMARK(BM_DiskConcentricInverse);
BENCHMARK(BM_DiskPdf);
BENCHMARK(BM_UniformSphere);
BENCHMARK(BM_UniformSpherePdf);
BENCHMARK(BM_UniformHemisphere);
BENCHMARK(BM_UniformHemispherePdf);
BENCHMARK(BM_CosineHemisphere);
BENCHMARK(BM_CosineHemispherePdf);
BENCHMARK(BM_UniformCone);
BENCHMARK(BM_UniformConePdf);
BENCHMARK(BM_UniformTriangle);
BENCHMARK(BM_UniformTrianglePdf);

// Truncated normal in its regimes: 0 = lens perturbation range, 1 = 3..4 sigma tail,
// 2 = 40 sigma (long double), 3 = narrow interval (quadrature + Newton).
TruncatedNormal tn_setting(int64_t k) {
  switch (k) {
    case 0: return *TruncatedNormal::create(0, 0.5, -kPi, kPi);
    case 1: return *TruncatedNormal::create(0, 1, 3, 4);
    case 2: return *TruncatedNormal::create(0, 1, 40, 41);
    default: return *TruncatedNormal::create(1, 2, 2, 2.000001);
  }
}
void BM_TruncatedNormalSample(benchmark::State& s) {
  const TruncatedNormal t = tn_setting(s.range(0));
  run_warp(s, [&](Vec2 u) { return t.sample(u.x); });
}
void BM_TruncatedNormalPdf(benchmark::State& s) {
  const TruncatedNormal t = tn_setting(s.range(0));
  run_warp(s, [&](Vec2 u) { return t.pdf(t.a() + u.x * (t.b() - t.a())); });
}
void BM_TruncatedNormalCdf(benchmark::State& s) {
  const TruncatedNormal t = tn_setting(s.range(0));
  run_warp(s, [&](Vec2 u) { return t.cdf(t.a() + u.x * (t.b() - t.a())); });
}
BENCHMARK(BM_TruncatedNormalSample)->DenseRange(0, 3);
BENCHMARK(BM_TruncatedNormalPdf)->DenseRange(0, 3);
BENCHMARK(BM_TruncatedNormalCdf)->DenseRange(0, 3);

std::vector<double> weights(int64_t n) {
  std::vector<double> w(static_cast<size_t>(n));
  Rng r(3);
  for (double& x : w) x = r.uniform();
  return w;
}
void BM_AliasSample(benchmark::State& s) {
  const AliasTable a = *AliasTable::create(weights(s.range(0)));
  run_warp(s, [&](Vec2 u) { return a.sample(u.x).index; });
}
void BM_AliasPmf(benchmark::State& s) {
  const AliasTable a = *AliasTable::create(weights(s.range(0)));
  run_warp(s, [&](Vec2 u) { return a.pmf(static_cast<size_t>(u.x * static_cast<double>(a.size()))); });
}
void BM_CdfSample(benchmark::State& s) {
  const DiscreteCdf d = *DiscreteCdf::create(weights(s.range(0)));
  run_warp(s, [&](Vec2 u) { return d.sample(u.x).index; });
}
BENCHMARK(BM_AliasSample)->Arg(16)->Arg(1 << 16);
BENCHMARK(BM_AliasPmf)->Arg(16)->Arg(1 << 16);
BENCHMARK(BM_CdfSample)->Arg(16)->Arg(1 << 16);

}  // namespace
}  // namespace tb

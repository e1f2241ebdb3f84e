// Throughput of every BSDF: eval() and sample() calls per second (Google Benchmark).
//   build-*/bench/material_bench --benchmark_counters_tabular=true
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "lib/core/rng.h"
#include "lib/material/bsdf_registry.h"

namespace tb {
namespace {

struct BenchCase {
  const char* label;
  const char* name;
  const char* params;
};
const BenchCase kCases[] = {
    {"lambert", "lambert", "{}"},
    {"smooth_conductor", "smooth_conductor", "{}"},
    {"smooth_dielectric", "smooth_dielectric", "{}"},
    {"rough_conductor_beckmann", "rough_conductor", R"({"distribution":"beckmann","alpha":0.2})"},
    {"rough_conductor_ggx", "rough_conductor", R"({"distribution":"ggx","alpha":0.2})"},
    {"rough_conductor_ggx_vndf", "rough_conductor", R"({"distribution":"ggx","alpha":0.2,"visible_normals":true})"},
    {"rough_dielectric_beckmann", "rough_dielectric", R"({"distribution":"beckmann","alpha":0.2})"},
    {"rough_dielectric_ggx", "rough_dielectric", R"({"distribution":"ggx","alpha":0.2})"},
    {"rough_dielectric_ggx_vndf", "rough_dielectric", R"({"distribution":"ggx","alpha":0.2,"visible_normals":true})"},
};

// 4096 pre-drawn (wo, wi, uc, u) so that the RNG is not measured.
struct Inputs {
  std::vector<Vec3> wo, wi;
  std::vector<double> uc;
  std::vector<Vec2> u;
  Inputs() {
    Rng r(42);
    auto dir = [&] {
      const double z = 2 * r.uniform() - 1, phi = 2 * kPi * r.uniform();
      const double s = std::sqrt(std::max(0.0, 1 - z * z));
      return Vec3(s * std::cos(phi), s * std::sin(phi), z);
    };
    for (int i = 0; i < 4096; ++i) {
      wo.push_back(dir());
      wi.push_back(dir());
      uc.push_back(r.uniform());
      u.push_back(r.uniform2());
    }
  }
};
const Inputs& inputs() {
  static const Inputs in;
  return in;
}

void BM_Eval(benchmark::State& state, const BenchCase& c) {
  const auto b = make_bsdf(c.name, nlohmann::json::parse(c.params));
  const Inputs& in = inputs();
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(b->eval(in.wo[i], in.wi[i], TransportMode::kRadiance));
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Sample(benchmark::State& state, const BenchCase& c) {
  const auto b = make_bsdf(c.name, nlohmann::json::parse(c.params));
  const Inputs& in = inputs();
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(b->sample(in.wo[i], in.uc[i], in.u[i], TransportMode::kRadiance));
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Pdf(benchmark::State& state, const BenchCase& c) {
  const auto b = make_bsdf(c.name, nlohmann::json::parse(c.params));
  const Inputs& in = inputs();
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(b->pdf(in.wo[i], in.wi[i], TransportMode::kRadiance));
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
}

[[maybe_unused]] const bool kRegistered = [] {
  for (const BenchCase& c : kCases) {
    benchmark::RegisterBenchmark((std::string("eval/") + c.label).c_str(), BM_Eval, c);
    benchmark::RegisterBenchmark((std::string("sample/") + c.label).c_str(), BM_Sample, c);
    benchmark::RegisterBenchmark((std::string("pdf/") + c.label).c_str(), BM_Pdf, c);
  }
  return true;
}();

}  // namespace
}  // namespace tb

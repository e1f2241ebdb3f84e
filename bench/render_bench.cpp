// Rendering throughput against the ray-tracing limit, in one run:
//  - BM_RawIntersect / BM_RawOccluded: raw Embree on the Cornell box (scenes/cornell-box.json):
//    incoherent float rays, origins uniform in the bounding box of the geometry and directions
//    uniform on the sphere (so that, as for path-traced rays, most of them hit a wall),
//    rtcIntersect1 / rtcOccluded1 with nothing around them;
//    1 and 2 threads (TBB, a fixed batch of 2^18 rays per iteration). Counter rays/s.
//  - BM_RawIntersectStream / BM_RawOccludedStream: the same rays as rtcIntersect1M /
//    rtcOccluded1M streams of 1024 (what a wavefront tracer could use; for comparison only).
//  - BM_PathTracerSegments: the path tracer on the same scene at its 256 x 256 resolution,
//    one pass of 1 or 4 spp per iteration (the film's per-pass work shows in the difference),
//    1 and 2 threads; segments/s counts every ray it casts (camera rays,
//    extensions, shadow rays), samples/s the camera samples.
//  - BM_PathTracerToRawRatio: the two alternately in each iteration (same load for both), the
//    ratio PT segments/s : raw rtcIntersect1 rays/s directly.
//  - BM_Integrator/<name>/<scene>: samples/s of every registered integrator except albedo on
//    every shipped scene (scenes/*.json) at 512 x 512, 1 spp per iteration, all threads.
//  - BM_Mcmc/<name>/threads:N: mutations/s of every MCMC integrator of the registry (the names
//    whose run report counts mutations) on the Cornell box at 128 x 128, 16 mutations per pixel
//    in 4 passes (or chains) per iteration, 1 and 2 threads; counter mutations/s is the
//    integrator's own figure (its mutation phase), wall/s includes bootstrap and start-up.
// Ratio to report: PT segments/s / raw rtcIntersect1 rays/s at 2 threads (target >= 0.5), and
// the thread scaling of each from 1 to 2 threads. The */cpu_s counters divide by the process's
// CPU time instead (all threads): on a shared machine they still compare PT with raw Embree.
#include <benchmark/benchmark.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>
#include <time.h>

#include "lib/core/atomic_file.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/core/warp_sphere.h"
#include "lib/integrator/path_tracer.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/scene_loader.h"

namespace tb {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(TB_SOURCE_DIR) / "scenes";

// A shipped scene, optionally at another resolution (cached: loading builds the BVH).
const World& scene(const std::string& file, int resolution = 0) {
  static std::map<std::pair<std::string, int>, std::unique_ptr<World>> cache;
  auto& w = cache[{file, resolution}];
  if (!w) {
    const std::string path = (kScenes / file).string();
    nlohmann::json j = scene_json_from_file(path);  // JSON, or Mitsuba XML translated
    if (resolution > 0) j["camera"]["resolution"] = {resolution, resolution};
    w = load_world_from_string(j.dump(), path, kScenes.string());
  }
  return *w;
}

constexpr size_t kRaysPerIteration = size_t{1} << 18;

// CPU seconds of the whole process (all threads): rates per CPU second are insensitive to
// other processes competing for the cores, unlike rates per wall-clock second.
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

const std::vector<RTCRay>& raw_rays() {
  static const std::vector<RTCRay> rays = [] {
    // The bounding box of the geometry (the Cornell box is made of triangle meshes only).
    const Scene& geo = scene("cornell-box.json").geometry();
    Vec3 lo(kInfinity), hi(-kInfinity);
    for (uint32_t id = 0; id < geo.shape_count(); ++id)
      for (const Vec3& p : geo.mesh(id).positions()) lo = glm::min(lo, p), hi = glm::max(hi, p);
    std::vector<RTCRay> r(kRaysPerIteration);
    Rng rng(2024);
    for (RTCRay& ray : r) {
      const Vec3 o = lo + Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * (hi - lo);
      const Vec3 d = sample_uniform_sphere(rng.uniform2());
      ray = RTCRay{};
      ray.org_x = float(o.x), ray.org_y = float(o.y), ray.org_z = float(o.z);
      ray.dir_x = float(d.x), ray.dir_y = float(d.y), ray.dir_z = float(d.z);
      ray.tnear = 0.0f;
      ray.tfar = std::numeric_limits<float>::infinity();
      ray.mask = 0xffffffffu;
    }
    return r;
  }();
  return rays;
}

// Traces the 2^18 raw rays once, in parallel over blocks of 1024 rays (enough work per task that
// scheduling is negligible): trace_block(first, ctx) traces rays [first, first + 1024) and returns
// its hits. Returns the number of hits.
template <class TraceBlock>
int64_t count_raw_hits(RTCIntersectContextFlags flags, TraceBlock&& trace_block) {
  std::atomic<int64_t> hits{0};
  parallel_for(raw_rays().size() / 1024, [&](size_t block) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = flags;
    hits.fetch_add(trace_block(block * 1024, &ctx), std::memory_order_relaxed);
  });
  return hits.load();
}

RTCScene raw_scene() { return static_cast<RTCScene>(scene("cornell-box.json").geometry().embree_scene()); }

// One query per ray (rtcIntersect1 / rtcOccluded1).
template <bool kOccluded>
int64_t trace_raw_rays() {
  const std::vector<RTCRay>& rays = raw_rays();
  const RTCScene rtc = raw_scene();  // looked up once, outside the timed queries
  return count_raw_hits(RTC_INTERSECT_CONTEXT_FLAG_NONE, [&](size_t first, RTCIntersectContext* ctx) {
    int64_t h = 0;
    for (size_t i = first; i < first + 1024; ++i) {
      if constexpr (kOccluded) {
        RTCRay r = rays[i];
        rtcOccluded1(rtc, ctx, &r);
        h += r.tfar < 0;
      } else {
        RTCRayHit rh;
        rh.ray = rays[i];
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(rtc, ctx, &rh);
        h += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      }
    }
    return h;
  });
}

// The same rays as streams of 1024 (rtcIntersect1M / rtcOccluded1M, incoherent flag): Embree
// regroups them into packets for its SIMD traversal.
template <bool kOccluded>
int64_t trace_raw_streams() {
  const std::vector<RTCRay>& rays = raw_rays();
  const RTCScene rtc = raw_scene();  // looked up once, outside the timed queries
  return count_raw_hits(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT, [&](size_t first, RTCIntersectContext* ctx) {
    int64_t h = 0;
    if constexpr (kOccluded) {
      std::vector<RTCRay> r(rays.begin() + first, rays.begin() + first + 1024);
      rtcOccluded1M(rtc, ctx, r.data(), 1024, sizeof(RTCRay));
      for (const RTCRay& x : r) h += x.tfar < 0;
    } else {
      std::vector<RTCRayHit> rh(1024);
      for (size_t i = 0; i < 1024; ++i) {
        rh[i].ray = rays[first + i];
        rh[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(rtc, ctx, rh.data(), 1024, sizeof(RTCRayHit));
      for (const RTCRayHit& x : rh) h += x.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    return h;
  });
}

template <bool kOccluded>
void raw_streams_bench(benchmark::State& state) {
  const std::vector<RTCRay>& rays = raw_rays();
  ThreadLimit limit(static_cast<size_t>(state.range(0)));
  int64_t hits = 0;
  for (auto _ : state) hits += trace_raw_streams<kOccluded>();
  const double n = double(state.iterations()) * double(rays.size());
  state.counters["rays/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  state.counters["hit_fraction"] = double(hits) / n;
}
void BM_RawIntersectStream(benchmark::State& state) { raw_streams_bench<false>(state); }
void BM_RawOccludedStream(benchmark::State& state) { raw_streams_bench<true>(state); }
BENCHMARK(BM_RawIntersectStream)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RawOccludedStream)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

template <bool kOccluded>
void raw_rays_bench(benchmark::State& state) {
  const std::vector<RTCRay>& rays = raw_rays();
  ThreadLimit limit(static_cast<size_t>(state.range(0)));
  int64_t hits = 0;
  const double cpu0 = process_cpu_seconds();
  for (auto _ : state) hits += trace_raw_rays<kOccluded>();
  const double cpu = process_cpu_seconds() - cpu0;
  const double n = double(state.iterations()) * double(rays.size());
  state.counters["rays/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  state.counters["rays/cpu_s"] = n / cpu;
  state.counters["hit_fraction"] = double(hits) / n;
}

void BM_RawIntersect(benchmark::State& state) { raw_rays_bench<false>(state); }
void BM_RawOccluded(benchmark::State& state) { raw_rays_bench<true>(state); }
BENCHMARK(BM_RawIntersect)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RawOccluded)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

// One pass of `spp` samples per pixel at the scene's own maximum depth.
RenderSettings one_pass(const World& w, int64_t spp) {
  RenderSettings st;
  st.spp = spp;
  st.passes = 1;
  st.max_depth = w.integrator_defaults().value("max_depth", 10);
  return st;
}

void BM_PathTracerSegments(benchmark::State& state) {
  const World& w = scene("cornell-box.json");
  ThreadLimit limit(static_cast<size_t>(state.range(0)));
  RenderSettings st = one_pass(w, state.range(1));
  RayCounts counts;
  uint64_t seed = 1;
  // One film for the run, as `tb render` keeps one over its passes (a new film per iteration
  // would time the page faults of its first writes).
  Film film(w.camera().width(), w.camera().height());
  const double cpu0 = process_cpu_seconds();
  for (auto _ : state) {
    st.seed = seed++;
    render_pt(w, st, film, &counts);
  }
  state.counters["segments/cpu_s"] = double(counts.total()) / (process_cpu_seconds() - cpu0);
  state.counters["segments/s"] = benchmark::Counter(double(counts.total()), benchmark::Counter::kIsRate);
  state.counters["shadow_fraction"] = double(counts.shadow) / double(counts.total());
  state.counters["segments/sample"] =
      double(counts.total()) / (double(state.iterations()) * double(w.camera().pixel_count() * st.spp));
  state.counters["samples/s"] = benchmark::Counter(
      double(state.iterations()) * double(w.camera().pixel_count() * st.spp), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PathTracerSegments)
    ->ArgsProduct({{1, 2}, {1, 4}})
    ->ArgNames({"threads", "spp_per_pass"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// PT segments/s over raw rtcIntersect1 rays/s measured alternately, a raw batch then a PT pass
// (256 x 256, 1 spp) per iteration, so that both see the same load on a shared machine.
void BM_PathTracerToRawRatio(benchmark::State& state) {
  const World& w = scene("cornell-box.json");
  ThreadLimit limit(static_cast<size_t>(state.range(0)));
  RenderSettings st = one_pass(w, 1);
  RayCounts counts;
  double t_raw = 0, t_pt = 0;
  int64_t raw = 0;
  uint64_t seed = 1;
  Film film(w.camera().width(), w.camera().height());
  for (auto _ : state) {
    st.seed = seed++;
    const auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(trace_raw_rays<false>());
    raw += int64_t(raw_rays().size());
    const auto t1 = std::chrono::steady_clock::now();
    render_pt(w, st, film, &counts);
    const auto t2 = std::chrono::steady_clock::now();
    t_raw += std::chrono::duration<double>(t1 - t0).count();
    t_pt += std::chrono::duration<double>(t2 - t1).count();
  }
  state.counters["raw_rays/s"] = double(raw) / t_raw;
  state.counters["pt_segments/s"] = double(counts.total()) / t_pt;
  state.counters["pt/raw"] = (double(counts.total()) / t_pt) / (double(raw) / t_raw);
}
BENCHMARK(BM_PathTracerToRawRatio)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)
    ->MinTime(3.0);

// samples/s of one integrator on one shipped scene at 512 x 512, 1 spp per iteration.
void integrator_bench(benchmark::State& state, const IntegratorInfo* integ, const std::string& file) {
  const World& w = scene(file, 512);
  RenderSettings st = one_pass(w, 1);
  uint64_t seed = 1;
  // One film for the run, as in BM_PathTracerSegments: a new 512 x 512 film per iteration timed
  // its allocation and first-touch page faults, serial work that is not the integrator's.
  Film film(w.camera().width(), w.camera().height());
  const double cpu0 = process_cpu_seconds();
  for (auto _ : state) {
    st.seed = seed++;
    integ->render(w, st, film);
  }
  const double samples = double(state.iterations()) * double(w.camera().pixel_count());
  state.counters["samples/s"] = benchmark::Counter(samples, benchmark::Counter::kIsRate);
  state.counters["samples/cpu_s"] = samples / (process_cpu_seconds() - cpu0);
}

// mutations/s of one MCMC integrator on the Cornell box, 128 x 128, 16 mutations per pixel.
void mcmc_bench(benchmark::State& state, const IntegratorInfo* integ) {
  const ThreadLimit limit(static_cast<size_t>(state.range(0)));
  const World& w = scene("cornell-box.json", 128);
  RenderSettings st;
  st.spp = 16;
  st.passes = 4;
  uint64_t seed = 1;
  double mutations = 0.0, mutation_seconds = 0.0;
  int64_t total = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    RunReport report;
    st.report = &report;
    st.seed = seed++;
    Film film(w.camera().width(), w.camera().height());
    integ->render(w, st, film);
    mutations += double(report.mutations_total);
    if (report.mutations_per_second > 0) mutation_seconds += double(report.mutations_total) / report.mutations_per_second;
    total += report.mutations_total;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  state.counters["mutations/s"] = mutation_seconds > 0 ? mutations / mutation_seconds : 0.0;
  state.counters["wall/s"] = wall > 0 ? double(total) / wall : 0.0;
}

// Registered at static initialisation (before benchmark_main runs): every integrator of the
// registry but albedo, on every scene file; every MCMC integrator on the Cornell box.
[[maybe_unused]] const bool kRegistered = [] {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kScenes))
    if (e.path().extension() == ".json") files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  for (const IntegratorInfo& integ : integrators()) {
    if (integ.name == "albedo") continue;
    for (const std::string& f : files)
      benchmark::RegisterBenchmark(("BM_Integrator/" + integ.name + "/" + f).c_str(), integrator_bench, &integ, f)
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(1.0);
    const bool mcmc = integ.name.find("mlt") != std::string::npos;
    if (mcmc)
      benchmark::RegisterBenchmark(("BM_Mcmc/" + integ.name).c_str(), mcmc_bench, &integ)
          ->Arg(1)
          ->Arg(2)
          ->ArgName("threads")
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond)
          ->MinTime(2.0);
  }
  return true;
}();

}  // namespace
}  // namespace tb

// Ray-query throughput (rays/s) of the geometry layer: Scene::intersect on a tessellated
// sphere with ~100k triangles and on each analytic shape, with incoherent random rays (origins
// on a sphere around the shape, directions towards random points inside its bounds). Each
// query includes the double-precision refinement and differential geometry of the hit.
#include <benchmark/benchmark.h>

#include <vector>

#include "lib/core/rng.h"
#include "lib/geometry/mesh_builders.h"
#include "lib/geometry/reference_shapes.h"
#include "lib/geometry/scene.h"

namespace tb {
namespace {

std::vector<Ray> incoherent_rays(const Bounds3& b, size_t n) {
  std::vector<Ray> rays(n);
  Rng rng(42);
  const Vec3 c = 0.5 * (b.lo + b.hi);
  const double radius = glm::length(b.diagonal());
  for (Ray& r : rays) {
    const double z = 1 - 2 * rng.uniform(), phi = 2 * kPi * rng.uniform(), s = safe_sqrt(1 - z * z);
    r.o = c + radius * Vec3(s * std::cos(phi), s * std::sin(phi), z);
    const Vec3 target = b.lo + Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * b.diagonal();
    r.d = glm::normalize(target - r.o);
  }
  return rays;
}

void run(benchmark::State& state, const Scene& scene, const std::vector<Ray>& rays) {
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    const auto h = scene.intersect(rays[i]);
    hits += h.has_value();
    benchmark::DoNotOptimize(h);
    if (++i == rays.size()) i = 0;
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["hit_fraction"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
}

void BM_IntersectMesh100k(benchmark::State& state) {
  static Scene* scene = [] {
    auto* s = new Scene;
    s->add(make_uv_sphere_mesh(1.0, 224, 224));  // 2 * 224 * 223 = 99,904 triangles
    s->commit();
    return s;
  }();
  static const std::vector<Ray> rays = incoherent_rays({Vec3(-1), Vec3(1)}, 1 << 16);
  run(state, *scene, rays);
}
BENCHMARK(BM_IntersectMesh100k);

void BM_IntersectAnalytic(benchmark::State& state) {
  static const std::vector<ReferenceShape> shapes = reference_analytic_shapes();
  const ReferenceShape& s = shapes[static_cast<size_t>(state.range(0))];
  state.SetLabel(s.name);
  Scene scene;
  scene.add(s.instance);
  scene.commit();
  const std::vector<Ray> rays = incoherent_rays(s.instance.world_bounds(), 1 << 16);
  run(state, scene, rays);
}
BENCHMARK(BM_IntersectAnalytic)->DenseRange(0, 8);

void BM_OccludedMesh100k(benchmark::State& state) {
  static Scene* scene = [] {
    auto* s = new Scene;
    s->add(make_uv_sphere_mesh(1.0, 224, 224));
    s->commit();
    return s;
  }();
  static const std::vector<Ray> rays = incoherent_rays({Vec3(-1), Vec3(1)}, 1 << 16);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(scene->occluded(rays[i]));
    if (++i == rays.size()) i = 0;
  }
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_OccludedMesh100k);

}  // namespace
}  // namespace tb

#include "lib/geometry/self_intersection.h"

#include <atomic>

#include "lib/core/frame.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/geometry/spawn.h"

namespace tb {

SelfIntersectionStats count_self_intersections(const Scene& scene, uint32_t shape_id,
                                               const SelfIntersectionOptions& o) {
  std::atomic<int64_t> self_hits{0}, leaks{0}, first_bad{o.rays};
  const bool mesh = scene.is_mesh(shape_id);
  parallel_for(static_cast<size_t>(o.rays), [&](size_t i) {
    Rng rng = Rng::for_sample(o.seed, o.key, i);
    const AreaSample s = scene.sample_area(shape_id, rng.uniform2());
    const Hit& h = s.hit;
    // Uniform direction on the hemisphere: cos theta uniform in (0, 1].
    const double cos_t = 1.0 - rng.uniform(), phi = 2 * kPi * rng.uniform();
    const double sin_t = safe_sqrt(1 - cos_t * cos_t);
    const bool inward = o.closed && (i % 2 == 1);
    const Frame f = Frame::from_z(inward ? -h.ng : h.ng);
    const Vec3 w = f.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t));
    const Ray ray = o.disable_offset ? Ray{h.p, w} : spawn_ray(h, w);
    const std::optional<Hit> hit = scene.intersect(ray);
    bool bad = false;
    if (hit && hit->shape_id == shape_id) {
      const bool near = glm::length(hit->p - h.p) < o.self_distance * o.size;
      if (near || (mesh && hit->prim_id == h.prim_id) || (o.convex && !inward)) {
        ++self_hits;
        bad = true;
      }
    }
    if (inward && !hit) {
      ++leaks;
      bad = true;
    }
    if (bad) {
      int64_t cur = first_bad.load();
      while (static_cast<int64_t>(i) < cur && !first_bad.compare_exchange_weak(cur, static_cast<int64_t>(i))) {
      }
    }
  });
  SelfIntersectionStats st;
  st.rays = o.rays;
  st.self_hits = self_hits.load();
  st.leaks = leaks.load();
  st.first_bad = first_bad.load() == o.rays ? -1 : first_bad.load();
  return st;
}

}  // namespace tb

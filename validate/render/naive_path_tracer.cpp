#include "validate/render/naive_path_tracer.h"

#include <algorithm>

#include "lib/core/rng.h"
#include "lib/film/film_parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/pass_loop.h"
#include "lib/path/scattering.h"

namespace tb {
namespace {

Rgb radiance(const World& world, Ray ray, int max_depth, Rng& rng) {
  Rgb L(0.0), beta(1.0);
  for (int depth = 0;; ++depth) {
    const auto hit = world.geometry().intersect(ray);
    const Vec3 wo = -glm::normalize(ray.d);
    if (!hit) {
      for (const Light* env : world.infinite_lights()) L += beta * env->le(Vec3(0.0), -wo);
      return L;
    }
    const SurfaceInfo& s = world.surface(hit->shape_id);
    if (s.emitter) L += beta * s.emitter->le(hit->n, wo);
    // `depth` scattering events so far; a further one is allowed while depth < max_depth.
    if (!s.bsdf || depth >= max_depth) return L;
    const SurfaceScatter sc(*hit, *s.bsdf);
    // Delta lights: the only way to reach them is an explicit connection (its density is the
    // Dirac mass itself, so the estimator is f |cos| I / d^2).
    for (const Light* light : world.lights()) {
      if (!light->is_delta()) continue;
      const Vec2 u = rng.uniform2();
      const auto ls = light->sample_li(hit->p, u);
      if (!ls || ls->pdf <= 0) continue;
      const Rgb f = sc.f(wo, ls->wi, TransportMode::kRadiance);
      if (f == Rgb(0.0)) continue;
      if (world.geometry().occluded(spawn_ray_to(*hit, ls->p_light))) continue;
      L += beta * f * sc.abs_cos_shading(ls->wi) * ls->li / ls->pdf;
    }
    const double uc = rng.uniform();
    const Vec2 u = rng.uniform2();
    const auto bs = sc.sample(wo, uc, u, TransportMode::kRadiance);
    if (!bs || bs->weight == Rgb(0.0)) return L;
    beta *= bs->weight;
    ray = spawn_ray(*hit, bs->wi);
  }
}

}  // namespace

int64_t render_naive_path_tracer(const World& world, const RenderSettings& st, Film& film) {
  const Camera& cam = world.camera();
  return run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    for_each_film_tile(film, 16, [&](FilmTile& tile) {
      for_each_camera_sample(tile, film.width(), st, pass, spp_pass, [&](int x, int y, uint64_t index, Rng& rng) {
        const Vec2 film_u = rng.uniform2();
        const Vec2 lens_u = rng.uniform2();
        const Vec2 raster(x + film_u.x, y + film_u.y);
        const CameraRay cr = cam.generate_ray(raster, lens_u);
        const Rgb v = cr.weight > 0 ? cr.weight * radiance(world, cr.ray, st.max_depth, rng) : Rgb(0.0);
        tile.add_sample(raster, v, index);
      });
    });
    return 0.0;
  });
}

}  // namespace tb

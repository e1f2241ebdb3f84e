#include "lib/integrator/albedo_integrator.h"


#include "lib/core/rng.h"
#include "lib/core/sample_dims.h"
#include "lib/film/film_parallel.h"
#include "lib/integrator/pass_loop.h"

namespace tb {

namespace {

Rgb primary_albedo(const World& world, const Ray& ray, Rng& rng) {
  const auto hit = world.geometry().intersect(ray);
  if (!hit) {
    Rgb l(0.0);
    for (const Light* env : world.infinite_lights()) l += env->le(Vec3(0.0), ray.d);
    return l;
  }
  const SurfaceInfo& s = world.surface(hit->shape_id);
  const Vec3 wo_world = -glm::normalize(ray.d);
  if (s.emitter) return s.emitter->le(hit->n, wo_world);
  if (!s.bsdf) return Rgb(0.0);
  Frame frame = Frame::from_z(hit->n);
  Vec3 wo = frame.to_local(wo_world);
  if (wo.z < 0 && !(s.bsdf->flags() & bsdf_flags::kTransmission)) wo.z = -wo.z;  // two-sided shading
  const double uc = rng.uniform();
  const Vec2 u = rng.uniform2();
  const auto bs = s.bsdf->sample(wo, uc, u, TransportMode::kRadiance);
  if (!bs) return Rgb(0.0);
  return bs->weight;
}

}  // namespace

int64_t render_albedo(const World& world, const RenderSettings& st, Film& film) {
  const Camera& cam = world.camera();
  return run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    for_each_film_tile(film, 16, [&](FilmTile& tile) {
      for_each_camera_sample(tile, film.width(), st, pass, spp_pass, [&](int x, int y, uint64_t index, Rng& rng) {
        const Vec2 film_u = rng.uniform2();  // CameraDim::kFilmX, kFilmY
        const Vec2 lens_u = rng.uniform2();  // CameraDim::kLensU, kLensV
        const Vec2 raster(x + film_u.x, y + film_u.y);
        const CameraRay cr = cam.generate_ray(raster, lens_u);
        const Rgb v = cr.weight > 0 ? cr.weight * primary_albedo(world, cr.ray, rng) : Rgb(0.0);
        tile.add_sample(raster, v, index);
      });
    });
    return 0.0;
  });
}

}  // namespace tb

#include "lib/integrator/bdpt.h"

#include "lib/integrator/bdpt_impl.h"

namespace tb {

using detail::random_walk;

int generate_camera_subpath(const PathContext& ctx, const Vec2& raster, const Vec2& lens_u, Uniforms& rng,
                            int max_vertices, std::vector<PathVertex>* path) {
  path->clear();
  if (max_vertices < 1) return 0;
  const Camera& cam = ctx.world->camera();
  // No differentials: the subpath never reads them (the same ray, a third of the camera's work).
  const CameraPrimaryRay cr = cam.generate_primary_ray(raster, lens_u);
  if (!(cr.weight > 0)) return 0;
  PathVertex z0;
  z0.kind = VertexKind::kCamera;
  z0.hit.p = cr.ray.o;
  z0.hit.n = z0.hit.ng = cam.projection().forward();
  z0.pdf_fwd = cam.pdf_we_pos(cr.ray);
  z0.beta = Rgb(cr.weight);
  path->push_back(z0);
  random_walk(ctx, rng, cr.ray, z0.beta, static_cast<size_t>(max_vertices),
              TransportMode::kRadiance, path);
  return static_cast<int>(path->size());
}

int generate_light_subpath(const PathContext& ctx, Uniforms& u, int max_vertices, std::vector<PathVertex>* path) {
  return detail::generate_light_subpath_with<ExactTerms>(ctx, u, max_vertices, path);
}

Connection connect_bdpt(const PathContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                        int s, int t, Uniforms& u) {
  return detail::connect_bdpt_with<ExactTerms>(ctx, light, camera, s, t, u);
}

int64_t render_bdpt(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_bdpt_with<ExactTerms>(world, st, film);
}

}  // namespace tb

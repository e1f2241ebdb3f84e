#include "lib/mcmc/path_space/subpath_step.h"

#include "lib/geometry/spawn.h"
#include "lib/light/area_light.h"
#include "lib/mcmc/path_space/path_state.h"
#include "lib/path/dirac.h"
#include "lib/path/scattering.h"

namespace tb::path_space {

namespace {

std::optional<PathVertex> trace_to_vertex(const PathContext& ctx, const Ray& ray) {
  const auto hit = ctx.world->geometry().intersect(ray);
  if (!hit) return std::nullopt;  // infinite lights are not targets of these mutations
  return surface_vertex(ctx, *hit);
}

bool emits(const PathVertex& v) { return v.light != nullptr && !v.infinite; }

}  // namespace

bool can_extend(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, TransportMode mode) {
  switch (cur.kind) {
    case VertexKind::kCamera:
      return mode == TransportMode::kRadiance && ctx.world->camera().lens_is_delta();
    case VertexKind::kLight:
      if (mode != TransportMode::kImportance || !emits(cur)) return false;
      return (cur.light->flags() & (light_flags::kArea | light_flags::kDeltaPosition)) != 0 &&
             (cur.light->flags() & light_flags::kArea ? dynamic_cast<const AreaLight*>(cur.light) != nullptr : true);
    case VertexKind::kSurface:
      break;
  }
  if (!prev) {  // an emitting surface as the first vertex of a light subpath
    return mode == TransportMode::kImportance && emits(cur) && dynamic_cast<const AreaLight*>(cur.light) != nullptr;
  }
  return cur.bsdf != nullptr;
}

std::optional<PathVertex> sample_next_vertex(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur,
                                             TransportMode mode, Uniforms& u, bool* cur_delta) {
  const double uc = u.next();
  const Vec2 u2 = u.next2();
  *cur_delta = false;
  if (!can_extend(ctx, prev, cur, mode)) return std::nullopt;
  if (cur.kind == VertexKind::kCamera) {
    const Camera& cam = ctx.world->camera();
    const Vec2 raster(u2.x * cam.width(), u2.y * cam.height());
    const CameraRay cr = cam.generate_ray(raster, Vec2(0.5));
    if (!(cr.weight > 0)) return std::nullopt;
    return trace_to_vertex(ctx, Ray{cur.hit.p, cr.ray.d});
  }
  if (!prev) {  // emission from the kept emitter point
    const Light& light = *cur.light;
    if (light.flags() & light_flags::kDeltaPosition) {
      const auto e = light.sample_le(Vec2(0.5), u2);
      if (!e || !(e->pdf_dir > 0)) return std::nullopt;
      return trace_to_vertex(ctx, Ray{cur.hit.p, e->ray.d});
    }
    const auto* area = dynamic_cast<const AreaLight*>(&light);
    const Vec3 w = sample_emission_direction(cur.hit.n, area->two_sided(), u2);
    if (!(pdf_emission_direction(cur.hit.n, area->two_sided(), w) > 0)) return std::nullopt;
    return trace_to_vertex(ctx, spawn_ray(cur.hit, w));
  }
  const SurfaceScatter sc(cur.hit, *cur.bsdf);
  const auto bs = sc.sample(direction(cur, *prev), uc, u2, mode);
  if (!bs || is_black(bs->weight) || !(bs->pdf > 0)) return std::nullopt;
  *cur_delta = bs->is_delta();
  return trace_to_vertex(ctx, spawn_ray(cur.hit, bs->wi));
}

std::optional<PathVertex> sample_emitter_vertex(const PathContext& ctx, Uniforms& u) {
  const double ul = u.next();
  const Vec2 up = u.next2();
  const auto choice = ctx.lights->sample(ul);
  if (!choice) return std::nullopt;
  const Light& light = *choice->light;
  if (light.flags() & light_flags::kInfinite) return std::nullopt;  // not supported as x_0 here
  const auto e = light.sample_le(up, Vec2(0.5));
  if (!e || !(e->pdf_pos > 0)) return std::nullopt;
  PathVertex v;
  v.kind = VertexKind::kLight;
  v.light = &light;
  v.hit = e->hit;
  v.delta = light.is_delta();
  return v;
}

}  // namespace tb::path_space

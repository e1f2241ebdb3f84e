#include "lib/mcmc/path_space/path_state.h"

#include "lib/path/dirac.h"

namespace tb::path_space {

Rgb PathTarget::contribution(const MltPath& x) const {
  if (x.v.size() < 2) return Rgb(0.0);
  return measurement_contribution(*ctx, x.v, true, DiracPolicy::kCoefficient);
}

double PathTarget::density(const MltPath& x) const {
  const double y = luminance(contribution(x));
  return y > 0.0 ? y : 0.0;
}

PathVertex surface_vertex(const PathContext& ctx, const Hit& hit) {
  PathVertex v;
  v.kind = VertexKind::kSurface;
  v.hit = hit;
  const SurfaceInfo& si = ctx.world->surface(hit.shape_id);
  v.bsdf = si.bsdf;
  v.light = si.emitter;
  v.delta = is_dirac_surface(v);  // a property of the material (lib/path/dirac.h)
  return v;
}

bool transmits_from_camera_side(const MltPath& x, int i) {
  return is_dirac_transmission(x.v[i], direction(x.v[i], x.v[i + 1]), direction(x.v[i], x.v[i - 1]));
}

bool transmits_from_light_side(const MltPath& x, int i) {
  return is_dirac_transmission(x.v[i], direction(x.v[i], x.v[i - 1]), direction(x.v[i], x.v[i + 1]));
}

bool same_vertex(const PathVertex& a, const PathVertex& b) {
  if (a.kind != b.kind || a.infinite != b.infinite) return false;
  if (a.infinite) return a.w_inf == b.w_inf;
  return a.hit.p == b.hit.p;
}

std::optional<Vec2> path_raster(const PathContext& ctx, const MltPath& x) {
  const size_t k = x.v.size() - 1;
  if (x.v.size() < 2) return std::nullopt;
  const auto h = ctx.world->camera().raster_from_ray(Ray{x.v[k].hit.p, direction(x.v[k], x.v[k - 1])});
  if (!h) return std::nullopt;
  return h->raster;
}

}  // namespace tb::path_space

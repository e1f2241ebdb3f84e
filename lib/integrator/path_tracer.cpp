#include "lib/integrator/path_tracer.h"

#include "lib/integrator/path_tracer_impl.h"

namespace tb {

Rgb pt_sample(const PathContext& ctx, const RenderSettings& st, const Vec2& raster, Uniforms& u) {
  return detail::pt_sample_with<ExactTerms>(ctx, st, raster, u);
}

void pt_sample_paths(const PathContext& ctx, const RenderSettings& st, const Vec2& raster, Uniforms& u,
                     std::vector<PathContribution>* out) {
  detail::pt_sample_paths_with<ExactTerms>(ctx, st, raster, u, out);
}

int64_t render_pt(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_pt_with<ExactTerms>(world, st, film, nullptr);
}

int64_t render_pt(const World& world, const RenderSettings& st, Film& film, RayCounts* counts) {
  return detail::render_pt_with<ExactTerms>(world, st, film, counts);
}

}  // namespace tb

#include "lib/integrator/light_tracer.h"

#include "lib/integrator/light_tracer_impl.h"

namespace tb {

int64_t render_lt(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_lt_with<ExactTerms>(world, st, film, nullptr);
}

int64_t render_lt(const World& world, const RenderSettings& st, Film& film, RayCounts* counts) {
  return detail::render_lt_with<ExactTerms>(world, st, film, counts);
}

}  // namespace tb

// A deliberately simple reference estimator for the analytic checks: path tracing by BSDF
// sampling only (no next-event estimation, no MIS, no Russian roulette), emission added where a
// path hits an emitter, the environment where it escapes; lights with a delta in position or
// direction (which no BSDF sample can hit) are connected explicitly at every vertex. Each
// term is the plain Monte Carlo estimator of the Neumann series (Veach 1997, Eq. 3.19 and
// Sec. 3.7.1) with throughput f |cos| / pdf, so its correctness depends only on the shared
// BSDF sampling (itself chi-square tested) and not on the light / MIS / path code of the
// integrators under test. It validates the exact images of analytic_worlds.h independently.
// Same signature as the registered integrators; max_depth = number of scattering events.
#pragma once

#include <cstdint>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

int64_t render_naive_path_tracer(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb

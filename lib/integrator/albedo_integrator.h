// Primary-hit albedo: for each camera ray, the emitted radiance of an emitter it hits, or the
// directional albedo rho(wo) = integral of f(wo, wi) |cos wi| dwi of the BSDF it hits,
// estimated by one BSDF sample (f |cos| / pdf, unbiased), or the environment radiance on a
// miss. A first image of any scene, and a check that scene, camera, geometry and BSDFs fit
// together. Surfaces are shaded two-sided: for a BSDF without transmission, a wo below the
// shading normal is mirrored to the front.
#pragma once

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

// Renders settings.passes passes into `film` (one Welch sample per pixel per pass); returns
// the number of passes done.
int64_t render_albedo(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb

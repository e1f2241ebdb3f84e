// Light tracing (particle tracing with connections to the camera; Veach 1997, Sec. 10.2.1 the
// (s, t = 1) techniques of BDPT alone; pbrt-v3 Sec. 16.3 with t = 1). Per pass N = P * spp_pass
// light paths start on an emitter chosen by LightSampler (Light::sample_le: area density
// pdf_pos, solid-angle density pdf_dir) and carry the importance-transport throughput
//     beta = Le |cos_light| / (pmf pdf_pos pdf_dir) * prod f_imp |cos wi| / pdf_bsdf.
// Every vertex that can scatter towards the camera (the emitted point itself, and every surface
// vertex with a non-delta BSDF) connects to a lens point by Camera::sample_wi and splats
//     beta * f_imp(wo, wc) |cos wc| * We / pdf_wi          (docs/camera.md)
// into the pixel it sees; the film scales the pass by P / N (Film::end_pass). Scattering uses
// SurfaceScatter in TransportMode::kImportance (adjoint BSDF with the shading-normal correction,
// Veach Sec. 5.3). Russian roulette as in the path tracer (after rr_min_depth scattering
// events, q = min(1, max component of beta), survivors divided by q).
//
// What light tracing cannot sample: emitters at infinity seen directly by the camera
// (environment and directional light: their emission disk lies outside the scene), and surfaces
// seen through delta BSDFs from a pinhole camera (the camera connection would need to hit a
// delta lobe). Those parts of an image are black.
//
// Random streams: Rng::for_sample(seed, kLightTracerKey, pass * N + path index).
#pragma once

#include <cstdint>

#include "lib/film/film.h"
#include "lib/integrator/path_tracer.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

int64_t render_lt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_lt(const World& world, const RenderSettings& settings, Film& film, RayCounts* counts);

}  // namespace tb

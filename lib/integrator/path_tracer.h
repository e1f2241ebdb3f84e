// Unidirectional path tracing with next-event estimation and multiple importance sampling
// (Veach 1997, Sec. 9.2.4 "direct lighting" combined at every vertex; pbrt-v3 Sec. 14.5
// PathIntegrator). At each surface vertex two techniques sample the next vertex when it lies on
// an emitter: a light sample (light chosen by LightSampler, Light::sample_li; solid-angle
// density pmf * pdf_li) and the BSDF sample that also extends the path (SurfaceScatter::sample;
// solid-angle density pdf_bsdf). Both are weighted by the power heuristic (beta = 2, Veach
// Eq. 9.13). Delta BSDF lobes and delta lights have only one technique and weight 1; emission
// reached by a camera ray or after a delta bounce counts fully. Russian roulette after
// rr_min_depth scattering events with survival probability q = min(1, max component of the
// throughput), survivors divided by q (pbrt-v3 Sec. 13.7).
//
// Dimensions: the camera uses CameraDim::*, every vertex draws the kDimsPerBounce uniforms of
// BounceDim in order (lib/core/sample_dims.h), used or not, so a decision always consumes the
// same uniform.
#pragma once

#include <cstdint>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/path/path.h"
#include "lib/scene/world.h"

namespace tb {

// Rays traced by a render (for the throughput benchmark, bench/render_bench.cpp).
struct RayCounts {
  int64_t extension = 0;  // closest-hit queries (camera rays and path extensions)
  int64_t shadow = 0;     // visibility queries (next-event estimation, camera connections)
  int64_t total() const { return extension + shadow; }
};

// Renders settings.passes passes (spp / passes samples per pixel each) into the film; returns
// the number of passes done. `counts`, when given, receives the rays traced.
int64_t render_pt(const World& world, const RenderSettings& settings, Film& film);
int64_t render_pt(const World& world, const RenderSettings& settings, Film& film, RayCounts* counts);

// One path-traced radiance sample through the raster position, its random numbers from u: the
// lens uniforms first, then kDimsPerBounce per vertex (as render_pt draws them). For PSSMLT over
// the path tracer (lib/mcmc/pss), where u is a primary-sample-space state.
Rgb pt_sample(const PathContext& ctx, const RenderSettings& settings, const Vec2& raster, Uniforms& u);

// The same sample split into the contributions of its paths (each next-event connection and each
// emitter hit is one path), with the variance-bounding ratio r~ of each (Zirr & Dachsbacher 2020,
// Eq. 21 with the MIS reduction of Sec. 6.6, as lib/differential/variance_bound.h
// subpath_variance_ratio computes it for a bidirectional camera subpath): a connection at vertex
// x_d (x_1 the first hit) has r~ = 1 + sum over the bounces m = 1..d-1 of p(i_1) / (p(i_m)
// |di_m / di_1|), an emitter hit at x_d the same sum to m = d - 2 (the direction that found it is
// MIS-weighted against next-event estimation), so direct illumination and directly seen emitters
// have r~ = 1. p(i_1) is the camera's solid-angle density per unit raster area (pinhole; a lens
// camera's aperture term is left out). The values sum to pt_sample's (same uniforms, same order
// of additions up to rounding). For the stratified target (lib/mcmc/pss/stratified_pss.h).
struct PathContribution {
  Rgb value{0.0};
  double ratio = 1.0;
};
void pt_sample_paths(const PathContext& ctx, const RenderSettings& settings, const Vec2& raster, Uniforms& u,
                     std::vector<PathContribution>* out);

}  // namespace tb

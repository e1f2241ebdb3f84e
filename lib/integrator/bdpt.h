// Bidirectional path tracing (Veach 1997, Ch. 10; Veach & Guibas 1995) on the shared path
// representation (lib/path/path.h): per pixel sample one camera subpath and one light subpath,
// every connection (s, t) with s + t - 2 <= max_depth scattering events and t >= 1, each
// weighted by the power (beta = 2) heuristic over all techniques that could have produced the
// same path. t = 1 connections (light subpath to the lens) are splatted; the rest are added to
// the pixel the camera subpath started in.
//
// RenderSettings::only_length / only_s restrict the estimator to paths of one length (segments)
// and to one unweighted technique (s, t = length + 1 - s), for the per-technique checks.
// The implementation is a template over the estimator's terms (bdpt_impl.h, estimator_terms.h)
// so that the negative controls of validate/ can get one term wrong without a switch here.
#pragma once

#include <span>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/path/path.h"
#include "lib/scene/world.h"

namespace tb {

int64_t render_bdpt(const World& world, const RenderSettings& settings, Film& film);

// One subpath (exposed for tests and for PSSMLT / MMLT over BDPT). Random numbers come from a
// Uniforms source (an RNG stream, or a primary-sample-space state of an MCMC chain).
// Camera subpath starting with the camera ray through `raster`; at most max_vertices vertices.
int generate_camera_subpath(const PathContext& ctx, const Vec2& raster, const Vec2& lens_u, Uniforms& u,
                            int max_vertices, std::vector<PathVertex>* path);
int generate_light_subpath(const PathContext& ctx, Uniforms& u, int max_vertices, std::vector<PathVertex>* path);

// The weighted contribution of technique (s, t) from two subpaths, and for t = 1 the raster
// position to splat to. Returns zero when the connection fails.
struct Connection {
  Rgb value{0.0};           // weighted contribution (unweighted when weight is 1)
  Rgb unweighted{0.0};
  double weight = 0.0;
  Vec2 raster{0.0};         // t = 1 only
  // The vertex sampled by the connection itself: the emitter point of s = 1 (replaces light[0])
  // or the lens point of t = 1 (replaces camera[0]); kind kSurface when there is none.
  PathVertex sampled;
};
Connection connect_bdpt(const PathContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                        int s, int t, Uniforms& u);

}  // namespace tb

// One sampling step of a subpath, shared by the path-space mutations: the vertex after `cur`
// (reached from `prev`; null at a subpath's first vertex) sampled as the integrators sample it,
// so that its area density is exactly pdf_next(ctx, prev, cur, next, mode) of lib/path/path.h:
//  - cur the camera (radiance mode): a uniform raster position over the whole image, the
//    Camera::pdf_we direction density (Dirac lens only: the lens point is kept);
//  - cur an emitter with prev null (importance mode): Light emission direction about the kept
//    emitter point (area lights: cosine-weighted, Light::pdf_le; Dirac-position lights:
//    Light::sample_le, whose direction does not depend on the position uniforms);
//  - cur a surface: the BSDF sample of SurfaceScatter (lib/path/scattering.h) with wo towards prev.
// A new emitter vertex x_0 (importance side) is sampled by the light sampler and the emitter's
// position density: density pdf_light_origin(). Both return nothing when the step fails (no
// direction, ray escapes, hit surface cannot continue). The uniforms used per step are fixed:
// 3 per direction step, 3 per emitter vertex.
#pragma once

#include <optional>

#include "lib/core/uniforms.h"
#include "lib/path/path.h"

namespace tb::path_space {

// May a direction be sampled from `cur` (kept end of a subpath) in this mode?
bool can_extend(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, TransportMode mode);

// Samples the next vertex. `cur_delta` receives whether the sampled lobe at cur was a Dirac one
// (the flag a walk stores on cur, lib/integrator/bdpt.cpp).
std::optional<PathVertex> sample_next_vertex(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur,
                                             TransportMode mode, Uniforms& u, bool* cur_delta);

// A fresh emitter vertex x_0: light by the light sampler, position by the emitter.
std::optional<PathVertex> sample_emitter_vertex(const PathContext& ctx, Uniforms& u);

}  // namespace tb::path_space

// Sample functions of primary-sample-space MLT: a map from the uniforms of a state (read through
// the streams of pss_state.h) to a list of splats (raster position, RGB value). The scalar target
// of the chain is I(u) = luminance(sum of the splat values) (Kelemen et al. 2002, Sec. 4: "the
// importance function", here the luminance as in pbrt-v3 Sec. 16.4.5). The driver (pss_driver.h)
// is generic over this form, so PSSMLT runs over BDPT, over a path tracer, or over one technique
// of one path length (MMLT) with the same code.
//
// Raster convention: the first two camera-stream uniforms pick the raster position uniformly over
// the whole image (density 1 / P in raster space, P = pixel count), so that
//   pixel_j = P * integral over [0,1)^inf of sum_c v_c(u) 1[raster_c(u) in pixel j] du
// is the same pixel measurement BDPT estimates (docs/mlt-pss.md, "Normalisation").
#pragma once

#include <functional>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/pss/pss_state.h"
#include "lib/path/path.h"

namespace tb::pss {

// The path a splat carries, for targets that need more than its value (a variance-bounding ratio,
// a half-vector walk): the subpaths it was connected from and its technique (s light vertices,
// t camera vertices; lib/path/path.h). A splat that sums several connections of the same subpaths
// (BDPT's camera-raster splat) has s = t = -1. The pointers are valid until the sample function is
// next evaluated on the same thread (the subpaths live in its thread-local buffers): a
// TargetFunction may read them, a splat kept across mutations may not. Empty for estimators that
// keep no vertices (radiance_sample_function).
struct SplatPath {
  const std::vector<PathVertex>* light = nullptr;
  const std::vector<PathVertex>* camera = nullptr;
  int s = -1, t = -1;
  bool empty() const { return light == nullptr && camera == nullptr; }
};

struct Splat {
  Vec2 raster{0.0};
  Rgb value{0.0};
  SplatPath path{};
  // > 0: the path's variance-bounding ratio r~, computed by the sample function (the path tracer's
  // paths keep no vertices; pt_paths_sample_function). 0: none (targets compute it from `path`).
  double ratio = 0.0;
};

// A sample function over a discrete level (the path length of MMLT; PSSMLT has one level) and
// the uniforms; appends its splats to `out` (which the caller clears). Must be thread-safe.
struct SampleFunction {
  int levels = 1;
  std::function<void(int level, StreamUniforms& u, std::vector<Splat>* out)> sample;
};

// I(u): luminance of the sum of the splat values (0 for an empty list).
double target_value(const std::vector<Splat>& splats);

// BDPT (lib/integrator/bdpt.h): one camera subpath (camera stream) and one light subpath (light
// stream), every connection (s, t) with s + t - 2 <= max_depth and t >= 1, power-heuristic
// weighted (connection stream). Connections with t >= 2 are summed into one splat at the camera
// raster; each t = 1 connection is its own splat at the raster it reaches.
SampleFunction bdpt_sample_function(const PathContext& ctx, int width, int height, int max_depth);

// MMLT (Hachisuka, Kaplanyan & Dachsbacher 2014, Sec. 4): level l is the path length k = l + 1
// segments (l = 0 .. max_depth). The first connection-stream uniform picks the technique
// s in {0 .. k} uniformly (t = k + 1 - s >= 1: t = 0 is never used, lib/path/path.h); the camera
// subpath must have exactly t vertices and the light subpath exactly s. The splat is the MIS-
// weighted contribution of that technique times the number of techniques, k + 1, so that its
// expectation over s is the sum over all techniques (the BDPT estimate of paths of length k).
SampleFunction mmlt_sample_function(const PathContext& ctx, int width, int height, int max_depth);

// A radiance estimator L(raster, u) seen as a sample function: raster from the first two camera-
// stream uniforms, the estimator reads the camera stream afterwards. For PSSMLT over the path
// tracer: pass pt_sample(ctx, settings, raster, u) of lib/integrator/path_tracer.h.
SampleFunction radiance_sample_function(int width, int height,
                                        std::function<Rgb(const Vec2& raster, Uniforms& u)> radiance);

// The path tracer with its sample split into paths (lib/integrator/path_tracer.h
// pt_sample_paths): one splat per next-event connection and per emitter hit, all at the sample's
// raster, each with its r~ in Splat::ratio. The sum of the splats is radiance_sample_function's
// single splat over pt_sample.
SampleFunction pt_paths_sample_function(const PathContext& ctx, const RenderSettings& settings, int width, int height);

}  // namespace tb::pss

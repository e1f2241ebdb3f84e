#include "lib/mcmc/pss/pss_sample.h"

#include "lib/integrator/path_tracer.h"

#include <algorithm>

#include "lib/integrator/bdpt.h"

namespace tb::pss {

double target_value(const std::vector<Splat>& splats) {
  Rgb sum(0.0);
  for (const Splat& s : splats) sum += s.value;
  return luminance(sum);
}

namespace {

Vec2 raster_from(StreamUniforms& u, int width, int height) {
  const double a = u.next(), b = u.next();
  return {a * width, b * height};
}

}  // namespace

SampleFunction bdpt_sample_function(const PathContext& ctx, int width, int height, int max_depth) {
  max_depth = std::max(0, max_depth);
  SampleFunction f;
  f.levels = 1;
  f.sample = [ctx, width, height, max_depth](int, StreamUniforms& u, std::vector<Splat>* out) {
    thread_local std::vector<PathVertex> cam, light;
    u.use_stream(kCameraStream);
    const Vec2 raster = raster_from(u, width, height);
    const Vec2 lens_u = u.next2();
    const int nc = generate_camera_subpath(ctx, raster, lens_u, u, max_depth + 2, &cam);
    u.use_stream(kLightStream);
    const int nl = generate_light_subpath(ctx, u, max_depth + 1, &light);
    u.use_stream(kConnectionStream);
    Rgb L(0.0);
    for (int t = 1; t <= nc; ++t)
      for (int s = 0; s <= nl; ++s) {
        if (s + t < 2 || s + t - 2 > max_depth) continue;
        const Connection c = connect_bdpt(ctx, light, cam, s, t, u);
        if (is_black(c.value)) continue;
        if (t == 1)
          out->push_back({c.raster, c.value, SplatPath{&light, &cam, s, t}});
        else
          L += c.value;
      }
    if (!is_black(L)) out->push_back({raster, L, SplatPath{&light, &cam, -1, -1}});
  };
  return f;
}

SampleFunction mmlt_sample_function(const PathContext& ctx, int width, int height, int max_depth) {
  max_depth = std::max(0, max_depth);
  SampleFunction f;
  f.levels = max_depth + 1;  // k = 1 .. max_depth + 1 segments
  f.sample = [ctx, width, height](int level, StreamUniforms& u, std::vector<Splat>* out) {
    thread_local std::vector<PathVertex> cam, light;
    const int k = level + 1, techniques = k + 1;
    u.use_stream(kConnectionStream);
    const int s = std::min(static_cast<int>(u.next() * techniques), techniques - 1);
    const int t = k + 1 - s;
    u.use_stream(kCameraStream);
    const Vec2 raster = raster_from(u, width, height);
    const Vec2 lens_u = u.next2();
    if (generate_camera_subpath(ctx, raster, lens_u, u, t, &cam) != t) return;
    u.use_stream(kLightStream);
    if (generate_light_subpath(ctx, u, s, &light) != s) return;
    u.use_stream(kConnectionStream);
    const Connection c = connect_bdpt(ctx, light, cam, s, t, u);
    if (is_black(c.value)) return;
    const Rgb v = c.value * static_cast<double>(techniques);
    out->push_back({t == 1 ? c.raster : raster, v, SplatPath{&light, &cam, s, t}});
  };
  return f;
}

SampleFunction radiance_sample_function(int width, int height,
                                        std::function<Rgb(const Vec2& raster, Uniforms& u)> radiance) {
  SampleFunction f;
  f.levels = 1;
  f.sample = [width, height, radiance = std::move(radiance)](int, StreamUniforms& u, std::vector<Splat>* out) {
    u.use_stream(kCameraStream);
    const Vec2 raster = raster_from(u, width, height);
    const Rgb L = radiance(raster, u);
    if (!is_black(L)) out->push_back({raster, L});
  };
  return f;
}

SampleFunction pt_paths_sample_function(const PathContext& ctx, const RenderSettings& settings, int width, int height) {
  SampleFunction f;
  f.levels = 1;
  f.sample = [ctx, settings, width, height](int, StreamUniforms& u, std::vector<Splat>* out) {
    thread_local std::vector<PathContribution> paths;
    u.use_stream(kCameraStream);
    const Vec2 raster = raster_from(u, width, height);
    paths.clear();
    pt_sample_paths(ctx, settings, raster, u, &paths);
    for (const PathContribution& p : paths) {
      Splat s;
      s.raster = raster;
      s.value = p.value;
      s.ratio = p.ratio;
      out->push_back(s);
    }
  };
  return f;
}

}  // namespace tb::pss

// BDPT as a template over the estimator's terms (estimator_terms.h): bdpt.cpp instantiates
// ExactTerms for render_bdpt, generate_light_subpath and connect_bdpt; the negative controls of
// validate/ instantiate broken terms. The algorithm is documented in bdpt.h.
#pragma once

#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "lib/core/parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/bdpt.h"
#include "lib/integrator/estimator_terms.h"
#include "lib/integrator/pass_loop.h"
#include "lib/path/scattering.h"

namespace tb::detail {

inline TransportMode opposite(TransportMode m) {
  return m == TransportMode::kRadiance ? TransportMode::kImportance : TransportMode::kRadiance;
}

inline double abs_cos(const Vec3& n, const Vec3& w) {
  return (n.x == 0 && n.y == 0 && n.z == 0) ? 1.0 : std::abs(glm::dot(n, w));
}

// Extends `path` (holding its first vertex) by sampling scattering events. For every new vertex
// its forward area density, and for the vertex two steps back its reverse one, are evaluated
// with pdf_next() on the vertex positions (not the sampled ray directions, which differ by the
// spawn offsets), so they equal what path_densities() computes for the finished path.
// Both densities at the scattering vertex path[m - 1] are evaluated with the SurfaceScatter that
// sampled its outgoing direction (`scatter`, built on its hit, which no push_back has moved since),
// so its shading frame is built once (pdf_next's overload: the same values).
inline void random_walk(const PathContext& ctx, Uniforms& rng, Ray ray, Rgb beta, size_t max_vertices,
                        TransportMode mode, std::vector<PathVertex>* path,
                        ImportanceCorrection correction = &importance_shading_correction) {
  const World& world = *ctx.world;
  std::optional<SurfaceScatter> scatter;  // at path->back() once it has scattered
  auto link = [&](PathVertex& v) {  // densities of the vertex just found, before it is pushed
    const size_t m = path->size();  // index v will take
    const PathVertex* before2 = m >= 2 ? &(*path)[m - 2] : nullptr;
    const SurfaceScatter* sc = scatter ? &*scatter : nullptr;
    v.pdf_fwd = pdf_next(ctx, before2, (*path)[m - 1], v, mode, sc);
    if (before2) (*path)[m - 2].pdf_rev = pdf_next(ctx, &v, (*path)[m - 1], *before2, opposite(mode), sc);
  };
  while (path->size() < max_vertices) {
    PathVertex v;  // the hit is written into v.hit in place (Scene::intersect(ray, Hit*))
    if (!world.geometry().intersect(ray, &v.hit)) {
      if (mode == TransportMode::kRadiance && !world.infinite_lights().empty()) {
        v.kind = VertexKind::kLight;
        v.infinite = true;
        v.w_inf = glm::normalize(ray.d);
        v.light = world.infinite_lights().front();
        v.delta = v.light->is_delta();
        v.beta = beta;
        link(v);
        path->push_back(v);
      }
      return;
    }
    v.kind = VertexKind::kSurface;
    const SurfaceInfo& si = world.surface(v.hit.shape_id);
    v.bsdf = si.bsdf;
    v.light = si.emitter;
    v.beta = beta;
    link(v);
    path->push_back(v);
    if (path->size() >= max_vertices || !v.bsdf) return;

    PathVertex& cur = path->back();
    const SurfaceScatter& sc = scatter.emplace(cur.hit, *cur.bsdf, correction);
    const Vec3 wo = -glm::normalize(ray.d);
    const double uc = rng.next();
    const Vec2 u = rng.next2();
    const auto bs = sc.sample(wo, uc, u, mode);
    if (!bs || is_black(bs->weight)) return;
    cur.delta = bs->is_delta();
    beta *= bs->weight;
    ray = spawn_ray(cur.hit, bs->wi);
  }
}

inline bool visible(const Scene& scene, const PathVertex& a, const PathVertex& b) {
  if (a.infinite || b.infinite) {
    const PathVertex& s = a.infinite ? b : a;
    const Vec3 w = a.infinite ? a.w_inf : b.w_inf;
    return !scene.occluded(spawn_ray(s.hit, w));
  }
  if (a.is_surface() && b.is_surface()) return !scene.occluded(spawn_ray_to(a.hit, b.hit));
  const PathVertex& s = a.is_surface() ? a : b;
  const PathVertex& o = a.is_surface() ? b : a;
  if (o.kind == VertexKind::kLight && o.light && (o.light->flags() & light_flags::kArea))
    return !scene.occluded(spawn_ray_to(s.hit, o.hit));
  return !scene.occluded(spawn_ray_to(s.hit, o.hit.p));
}

// The MIS weight of technique s for the path x_0..x_k made of light[0..s) and camera[t-1..0],
// with `x0` / `xk` replacing the sampled end vertices of s = 1 / t = 1 connections.
// light_scatter / camera_scatter (null: none): SurfaceScatters the connection built on the
// connected vertices x_{s-1} and x_s; their densities are evaluated with them (pdf_next's
// overload: the same values, each shading frame built once). The densities live in fixed arrays
// on the stack, only their first k + 1 entries written and read.
template <class Terms>
double connection_weight(const PathContext& ctx, std::span<const PathVertex> light, std::span<const PathVertex> camera,
                         int s, int t, const PathVertex* x0_override, const PathVertex* xk_override,
                         const SurfaceScatter* light_scatter = nullptr, const SurfaceScatter* camera_scatter = nullptr) {
  constexpr int kMaxVertices = 128;
  const int k = s + t - 1;
  if (k + 1 > kMaxVertices) return 0.0;
  auto X = [&](int i) -> const PathVertex& {
    if (i == 0 && x0_override) return *x0_override;
    if (i == k && xk_override) return *xk_override;
    return i < s ? light[static_cast<size_t>(i)] : camera[static_cast<size_t>(k - i)];
  };

  std::array<double, kMaxVertices> pL, pE, q;
  std::array<uint8_t, kMaxVertices> delta;
  for (int i = 0; i <= k; ++i) {
    const PathVertex& v = X(i);
    delta[i] = v.delta ? 1 : 0;
    if (i < s) {
      pL[i] = v.pdf_fwd;
      pE[i] = v.pdf_rev;
    } else {
      pE[i] = v.pdf_fwd;
      pL[i] = v.pdf_rev;
    }
  }
  // Densities that depend on the connection (pbrt-v3 Sec. 16.3.4 updates the same four).
  if (s >= 1)
    pE[s - 1] = pdf_next(ctx, t >= 2 ? &X(s + 1) : nullptr, X(s), X(s - 1), TransportMode::kRadiance, camera_scatter);
  if (s >= 2) pE[s - 2] = pdf_next(ctx, &X(s), X(s - 1), X(s - 2), TransportMode::kRadiance, light_scatter);
  if (s == 0) {
    pL[0] = pdf_light_origin(ctx, X(0));
    if (k >= 2) pL[1] = pdf_light_next(X(0), X(1));
  }
  if (s >= 1 && s < k)
    pL[s] = pdf_next(ctx, s >= 2 ? &X(s - 2) : nullptr, X(s - 1), X(s), TransportMode::kImportance, light_scatter);
  if (s >= 1 && s + 1 < k)
    pL[s + 1] = pdf_next(ctx, &X(s - 1), X(s), X(s + 1), TransportMode::kImportance, camera_scatter);
  if constexpr (!Terms::kMisFullDenominator) {  // one density left out of the denominator (read as 1)
    if (s >= 1)
      pE[s - 1] = 1.0;
    else
      pL[0] = 1.0;
  }
  const size_t n = static_cast<size_t>(k + 1);
  technique_ratios(PathDensitySpans{pL.data(), pE.data(), delta.data(), n, X(0).infinite}, s, q.data());
  return mis_weight_from_ratios(std::span<const double>(q.data(), n), s, MisKind::kPower);
}

template <class Terms>
int generate_light_subpath_with(const PathContext& ctx, Uniforms& rng, int max_vertices, std::vector<PathVertex>* path) {
  path->clear();
  if (max_vertices < 1) return 0;
  const auto choice = ctx.lights->sample(rng.next());
  const Vec2 u_pos = rng.next2(), u_dir = rng.next2();
  if (!choice) return 0;
  const Light& light = *choice->light;
  const auto e = light.sample_le(u_pos, u_dir);
  if (!e || !(e->pdf_pos > 0) || !(e->pdf_dir > 0) || is_black(e->le)) return 0;
  PathVertex y0;
  y0.kind = VertexKind::kLight;
  y0.light = &light;
  y0.hit = e->hit;
  y0.delta = light.is_delta();
  y0.infinite = (light.flags() & light_flags::kInfinite) != 0;
  y0.w_inf = -e->ray.d;
  y0.pdf_fwd = choice->pmf * (y0.infinite ? e->pdf_dir : e->pdf_pos);
  y0.beta = Rgb(1.0 / y0.pdf_fwd);  // times the emitted radiance at a t = 1 connection
  path->push_back(y0);
  const double cos0 = y0.infinite ? 1.0 : abs_cos(e->n, e->ray.d);
  const Rgb beta = e->le * cos0 / (choice->pmf * e->pdf_pos * e->pdf_dir);
  const bool area = (light.flags() & light_flags::kArea) != 0;
  const Ray ray = area ? spawn_ray(e->hit, e->ray.d) : e->ray;
  random_walk(ctx, rng, ray, beta, static_cast<size_t>(max_vertices), TransportMode::kImportance, path,
              Terms::kImportanceCorrection);
  return static_cast<int>(path->size());
}

template <class Terms>
Connection connect_bdpt_with(const PathContext& ctx, std::span<const PathVertex> light,
                             std::span<const PathVertex> camera, int s, int t, Uniforms& rng) {
  Connection c;
  if (t < 1 || s < 0 || s > static_cast<int>(light.size()) || t > static_cast<int>(camera.size())) return c;
  const World& world = *ctx.world;
  const Scene& scene = world.geometry();
  const PathVertex& ct = camera[t - 1];
  if (s == 0) {
    if (t < 2 || !ct.light) return c;
    if (!ct.infinite) {
      c.unweighted = ct.beta * emitted(ct, camera[t - 2]);
      if (is_black(c.unweighted)) return c;
      c.weight = connection_weight<Terms>(ctx, light, camera, s, t, nullptr, nullptr);
      c.value = c.unweighted * c.weight;
      return c;
    }
    for (const Light* env : world.infinite_lights()) {  // each environment is its own emitter
      PathVertex x0 = ct;
      x0.light = env;
      x0.delta = env->is_delta();
      const Rgb u = ct.beta * emitted(x0, camera[t - 2]);
      if (is_black(u)) continue;
      const double w = connection_weight<Terms>(ctx, light, camera, s, t, &x0, nullptr);
      c.unweighted += u;
      c.value += u * w;
    }
    c.weight = 1.0;
    return c;
  }
  const PathVertex& ls = light[s - 1];
  if (t == 1) {
    if (!ls.connectible() || ls.infinite) return c;
    const Camera& cam = world.camera();
    const auto cs = cam.sample_wi(ls.hit.p, rng.next2());
    if (!cs || !(cs->pdf > 0) || !(cs->importance > 0)) return c;
    PathVertex xk;
    xk.kind = VertexKind::kCamera;
    xk.hit.p = cs->lens_point;
    xk.hit.n = xk.hit.ng = cam.projection().forward();
    xk.pdf_fwd = cam.pdf_we_pos(Ray{cs->lens_point, -cs->wi});
    xk.beta = Rgb(cs->importance / cs->pdf);
    Rgb fs;
    std::optional<SurfaceScatter> sc_l;  // at ls when it scatters (s >= 2), shared with the MIS weight
    if (s == 1)
      fs = emitted(ls, xk);
    else
      fs = sc_l.emplace(ls.hit, *ls.bsdf, Terms::kImportanceCorrection)
               .f(direction(ls, light[s - 2]), cs->wi, TransportMode::kImportance);
    c.unweighted = ls.beta * fs * abs_cos(ls.shading_normal(), cs->wi) * xk.beta;
    if (is_black(c.unweighted) || !visible(scene, ls, xk)) {
      c.unweighted = Rgb(0.0);
      return c;
    }
    c.raster = cs->raster;
    c.sampled = xk;
    c.weight = connection_weight<Terms>(ctx, light, camera, s, t, nullptr, &xk, sc_l ? &*sc_l : nullptr, nullptr);
    c.value = c.unweighted * c.weight;
    return c;
  }
  if (!ct.connectible() || ct.kind != VertexKind::kSurface) return c;
  if (s == 1) {  // next-event estimation: a fresh emitter vertex from Light::sample_li
    const auto choice = ctx.lights->sample(rng.next());
    const Vec2 u = rng.next2();
    if (!choice) return c;
    const auto li = choice->light->sample_li(ct.hit.p, u);
    if (!li || !(li->pdf > 0) || is_black(li->li)) return c;
    PathVertex x0;
    x0.kind = VertexKind::kLight;
    x0.light = choice->light;
    x0.hit = li->hit;
    x0.delta = choice->light->is_delta();
    x0.infinite = (choice->light->flags() & light_flags::kInfinite) != 0;
    x0.w_inf = li->wi;
    x0.pdf_fwd = pdf_light_origin(ctx, x0);
    const SurfaceScatter sc_c(ct.hit, *ct.bsdf);  // shared with the MIS weight
    const Rgb fs = sc_c.f(direction(ct, camera[t - 2]), li->wi, TransportMode::kRadiance);
    const double cosine = Terms::kNeeReceiverCosine ? abs_cos(ct.shading_normal(), li->wi) : 1.0;
    c.unweighted = ct.beta * fs * cosine * li->li / (choice->pmf * li->pdf);
    if (is_black(c.unweighted) || !visible(scene, ct, x0)) {
      c.unweighted = Rgb(0.0);
      return c;
    }
    c.sampled = x0;
    c.weight = connection_weight<Terms>(ctx, std::span<const PathVertex>(&x0, 1), camera, s, t, &x0, nullptr, nullptr,
                                        &sc_c);
    c.value = c.unweighted * c.weight;
    return c;
  }
  if (!ls.connectible() || ls.kind != VertexKind::kSurface) return c;
  const Vec3 d = ct.hit.p - ls.hit.p;
  const double d2 = glm::dot(d, d);
  if (!(d2 > 0)) return c;
  const Vec3 w = d / std::sqrt(d2);  // from the light side to the camera side
  // Both scatters are shared with the MIS weight (its four connection densities sit at ls and ct).
  const SurfaceScatter sc_l(ls.hit, *ls.bsdf, Terms::kImportanceCorrection);
  const SurfaceScatter sc_c(ct.hit, *ct.bsdf);
  const Rgb fl = sc_l.f(direction(ls, light[s - 2]), w, TransportMode::kImportance);
  const Rgb fc = sc_c.f(direction(ct, camera[t - 2]), -w, TransportMode::kRadiance);
  const double g = abs_cos(ls.shading_normal(), w) * abs_cos(ct.shading_normal(), w) / d2;
  c.unweighted = ls.beta * fl * g * fc * ct.beta;
  if (is_black(c.unweighted) || !visible(scene, ls, ct)) {
    c.unweighted = Rgb(0.0);
    return c;
  }
  c.weight = connection_weight<Terms>(ctx, light, camera, s, t, nullptr, nullptr, &sc_l, &sc_c);
  c.value = c.unweighted * c.weight;
  return c;
}

template <class Terms>
int64_t render_bdpt_with(const World& world, const RenderSettings& st, Film& film) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const int max_depth = std::max(0, st.max_depth);
  const int max_cam = max_depth + 2, max_light = max_depth + 1;
  constexpr int kTile = 16;
  const int tx = (film.width() + kTile - 1) / kTile, ty = (film.height() + kTile - 1) / kTile;
  const size_t tiles = static_cast<size_t>(tx) * static_cast<size_t>(ty);
  constexpr size_t kBatch = 64;  // tiles per batch: bounds the splat memory, independent of threads
  return run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    for (size_t first = 0; first < tiles; first += kBatch) {
      const size_t count = std::min(kBatch, tiles - first);
      std::vector<FilmTile> film_tiles;
      std::vector<SplatBuffer> splats(count, SplatBuffer(film.width(), film.height()));
      film_tiles.reserve(count);
      for (size_t b = 0; b < count; ++b) {
        const int i = static_cast<int>((first + b) % static_cast<size_t>(tx)), j = static_cast<int>((first + b) / static_cast<size_t>(tx));
        film_tiles.push_back(film.make_tile({i * kTile, j * kTile, std::min(film.width(), (i + 1) * kTile),
                                             std::min(film.height(), (j + 1) * kTile)}));
      }
      parallel_for(count, [&](size_t b) {
        FilmTile& tile = film_tiles[b];
        SplatBuffer& sb = splats[b];
        std::vector<PathVertex> cam_path, light_path;
        cam_path.reserve(static_cast<size_t>(max_cam));
        light_path.reserve(static_cast<size_t>(max_light));
        for_each_camera_sample(tile, film.width(), st, pass, spp_pass, [&](int x, int y, uint64_t index, Rng& stream) {
              RngUniforms rng(stream);
              const Vec2 film_u = rng.next2();
              const Vec2 lens_u = rng.next2();
              const Vec2 raster(x + film_u.x, y + film_u.y);
              const int nc = generate_camera_subpath(ctx, raster, lens_u, rng, max_cam, &cam_path);
              const int nl = generate_light_subpath_with<Terms>(ctx, rng, max_light, &light_path);
              Rgb L(0.0);
              for (int t = 1; t <= nc; ++t)
                for (int s = 0; s <= nl; ++s) {
                  const int length = s + t - 1;
                  if (length < 1 || s + t - 2 > max_depth) continue;
                  if (st.only_length >= 0 && length != st.only_length) continue;
                  if (st.only_s >= 0 && s != st.only_s) continue;
                  const Connection c = connect_bdpt_with<Terms>(ctx, light_path, cam_path, s, t, rng);
                  const Rgb v = st.only_s >= 0 ? c.unweighted : c.value;
                  if (is_black(v)) continue;
                  if (t == 1)
                    sb.splat(c.raster, v, index);
                  else
                    L += v;
                }
              tile.add_sample(raster, L, index);
        });
      });
      for (size_t b = 0; b < count; ++b) {
        film.merge_tile(film_tiles[b]);
        film.merge_splats(splats[b]);
      }
    }
    return 1.0 / static_cast<double>(spp_pass);
  });
}

}  // namespace tb::detail

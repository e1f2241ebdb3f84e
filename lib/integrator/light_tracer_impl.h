// The light tracer as a template over the estimator's terms (estimator_terms.h): light_tracer.cpp
// instantiates ExactTerms for render_lt; the negative controls of validate/ instantiate broken
// terms. The algorithm is documented in light_tracer.h.
#pragma once

#include <array>
#include <atomic>
#include <optional>
#include <stdexcept>

#include "lib/core/rng.h"
#include "lib/film/film_parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/estimator_terms.h"
#include "lib/integrator/light_tracer.h"
#include "lib/integrator/pass_loop.h"
#include "lib/path/light_sampler.h"
#include "lib/path/scattering.h"

namespace tb::detail {

// Key of the light tracer's random streams (ASCII "lt"); index = pass * N + path.
inline constexpr uint64_t kLightTracerKey = 0x6c74;

// Uniforms of a light path, drawn in this order: the emission (light choice, position,
// direction, lens point of the emitted point's camera connection), then per surface vertex the
// lens point, the BSDF lobe and direction, and Russian roulette.
enum class EmitDim : size_t { kLightSelect, kPosU, kPosV, kDirU, kDirV, kLensU, kLensV, kCount };
enum class VertexDim : size_t { kLensU, kLensV, kBsdfLobe, kBsdfU, kBsdfV, kRussianRoulette, kCount };

template <class Dim>
struct DimUniforms {
  std::array<double, static_cast<size_t>(Dim::kCount)> u;
  explicit DimUniforms(Rng& rng) {
    for (double& v : u) v = rng.uniform();
  }
  double operator[](Dim d) const { return u[static_cast<size_t>(d)]; }
};

template <class Terms>
class LightTracer {
 public:
  LightTracer(const World& world, const RenderSettings& st) : world_(world), st_(st), lights_(world) {}

  void trace(Rng& rng, uint64_t index, SplatBuffer& out, RayCounts& counts) const {
    const Scene& scene = world_.geometry();
    const Camera& cam = world_.camera();
    const DimUniforms<EmitDim> ue(rng);
    const auto choice = lights_.sample(ue[EmitDim::kLightSelect]);
    if (!choice) return;
    const Light& light = *choice->light;
    const Vec2 u_pos(ue[EmitDim::kPosU], ue[EmitDim::kPosV]);
    const auto le = light.sample_le(u_pos, {ue[EmitDim::kDirU], ue[EmitDim::kDirV]});
    if (!le || !(le->pdf_pos > 0) || !(le->pdf_dir > 0)) return;
    const double pdf_emit = choice->pmf * le->pdf_pos;  // area density of the emitted point

    // The emitted point: area lights are re-sampled with the same uniforms for the full hit
    // record (its error bounds, for spawning rays off the emitter).
    std::optional<Hit> on_light;
    if (light.flags() & light_flags::kArea) {
      on_light = scene.sample_area(static_cast<const AreaLight&>(light).shape_id(), u_pos).hit;
      if (on_light->p != le->ray.o)
        throw std::logic_error("light tracer: AreaLight::sample_le no longer samples Scene::sample_area(u_pos)");
    }
    const Vec2 lens_emit(ue[EmitDim::kLensU], ue[EmitDim::kLensV]);
    if (!(light.flags() & light_flags::kInfinite))
      connect_emitter(light, on_light, le->ray.o, lens_emit, pdf_emit, index, out, counts);

    const bool has_normal = le->n != Vec3(0.0);
    const double cos_emit = has_normal ? std::abs(glm::dot(le->n, le->ray.d)) : 1.0;
    Rgb beta = le->le * (cos_emit / (pdf_emit * le->pdf_dir));
    if (is_black(beta)) return;
    Ray ray = on_light ? spawn_ray(*on_light, le->ray.d) : le->ray;

    for (int depth = 0; depth < st_.max_depth; ++depth) {
      ++counts.extension;
      const std::optional<Hit> hit = scene.intersect(ray);
      if (!hit) break;
      const SurfaceInfo& surf = world_.surface(hit->shape_id);
      if (!surf.bsdf) break;
      const SurfaceScatter scatter(*hit, *surf.bsdf, Terms::kImportanceCorrection);
      const Vec3 wo = -ray.d;
      const DimUniforms<VertexDim> u(rng);

      // Connection to the camera: a path with depth + 1 scattering events.
      if (surf.bsdf->flags() & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy)) {
        const auto ws = cam.sample_wi(hit->p, {u[VertexDim::kLensU], u[VertexDim::kLensV]});
        if (ws && ws->importance > 0 && ws->pdf > 0) {
          const Rgb f = scatter.f(wo, ws->wi, TransportMode::kImportance);
          if (!is_black(f)) {
            ++counts.shadow;
            if (!scene.occluded(spawn_ray_to(*hit, ws->lens_point)))
              out.splat(ws->raster, beta * f * (scatter.abs_cos_shading(ws->wi) * ws->importance / ws->pdf), index);
          }
        }
      }
      if (depth + 1 >= st_.max_depth) break;  // a longer path would exceed max_depth

      const auto bs = scatter.sample(wo, u[VertexDim::kBsdfLobe], {u[VertexDim::kBsdfU], u[VertexDim::kBsdfV]},
                                     TransportMode::kImportance);
      if (!bs || is_black(bs->weight)) break;
      beta *= bs->weight;
      ray = spawn_ray(*hit, bs->wi);
      if (st_.russian_roulette && depth + 1 >= st_.rr_min_depth) {
        const double q = std::min(1.0, max_component(beta));
        if (!(u[VertexDim::kRussianRoulette] < q)) break;
        if constexpr (Terms::kRouletteDividesByQ) beta /= q;
      }
    }
  }

 private:
  // The emitted point seen directly by the camera (zero scattering events): Le |cos_light| We /
  // (pdf_emit pdf_wi). Delta-position lights give their intensity towards the lens through
  // sample_li from the lens point (I / d^2, so multiplied back by d^2).
  void connect_emitter(const Light& light, const std::optional<Hit>& on_light, const Vec3& p, const Vec2& lens_u,
                       double pdf_emit, uint64_t index, SplatBuffer& out, RayCounts& counts) const {
    const auto ws = world_.camera().sample_wi(p, lens_u);
    if (!ws || !(ws->importance > 0) || !(ws->pdf > 0)) return;
    Rgb v(0.0);
    Ray shadow;
    if (on_light) {
      v = light.le(on_light->n, ws->wi) * std::abs(glm::dot(on_light->n, ws->wi));
      shadow = spawn_ray_to(*on_light, ws->lens_point);
    } else {
      const auto ls = light.sample_li(ws->lens_point, Vec2(0.5));
      if (!ls) return;
      v = ls->li * (ws->distance * ws->distance);
      shadow = Ray{p, ws->lens_point - p, 0.0, 1 - kShadowEpsilon};
    }
    if (is_black(v)) return;
    ++counts.shadow;
    if (world_.geometry().occluded(shadow)) return;
    out.splat(ws->raster, v * (ws->importance / (ws->pdf * pdf_emit)), index);
  }

  const World& world_;
  const RenderSettings& st_;
  LightSampler lights_;
};


template <class Terms>
int64_t render_lt_with(const World& world, const RenderSettings& st, Film& film, RayCounts* counts) {
  const LightTracer<Terms> lt(world, st);
  // Chunks depend only on the number of paths, so the merge order (and the image) is the same for
  // any thread count.
  constexpr uint64_t kChunk = 4096;
  std::atomic<int64_t> n_ext{0}, n_shadow{0};
  const int64_t done = run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    const uint64_t n = static_cast<uint64_t>(film.pixel_count() * spp_pass);  // light paths per pass
    const uint64_t first = static_cast<uint64_t>(pass) * n;
    splat_parallel(film, n, kChunk, [&](uint64_t s, SplatBuffer& buf) {
      RayCounts rc;
      Rng rng = Rng::for_sample(st.seed, kLightTracerKey, first + s);
      lt.trace(rng, first + s, buf, rc);
      if (counts) {  // shared counters only when asked for (benchmarks)
        n_ext.fetch_add(rc.extension, std::memory_order_relaxed);
        n_shadow.fetch_add(rc.shadow, std::memory_order_relaxed);
      }
    });
    return static_cast<double>(film.pixel_count()) / static_cast<double>(n);
  });
  if (counts) {
    counts->extension += n_ext.load();
    counts->shadow += n_shadow.load();
  }
  return done;
}

}  // namespace tb::detail

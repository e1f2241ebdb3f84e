// Photon mapping (pm) and stochastic progressive photon mapping (sppm) as templates over their
// kernel's normalisation (PhotonTerms): photon_map.cpp instantiates the exact terms; the negative
// controls of validate/render/broken_integrators.h instantiate broken ones. The algorithm is
// documented in photon_map.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/film/film_parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/pass_loop.h"
#include "lib/integrator/photon_map.h"
#include "lib/path/light_sampler.h"
#include "lib/path/scattering.h"

namespace tb {

// The density-estimation kernel: the constant kernel on the disk of radius r, normalised by its
// area (the density of N points of total weight W spread uniformly is W / (N pi r^2)).
struct PhotonTerms {
  static double kernel_area(double r) { return std::numbers::pi * r * r; }
};

namespace detail {

// Key of the photon streams (ASCII "pm"); index = global photon index.
inline constexpr uint64_t kPhotonKey = 0x706d;
inline constexpr uint64_t kPhotonChunk = 4096;

// Photon paths: the light tracer's emission and scattering (light_tracer_impl.h), storing a photon
// at every vertex with a non-delta lobe instead of connecting to the camera. Uniforms in order:
// light choice, position (2), direction (2); per vertex lobe, direction (2), roulette.
class PhotonTracer {
 public:
  PhotonTracer(const World& world, const RenderSettings& st) : world_(world), st_(st), lights_(world) {}

  void trace(Rng& rng, std::vector<Photon>& out) const {
    const Scene& scene = world_.geometry();
    const double u_sel = rng.uniform();
    const Vec2 u_pos = rng.uniform2();
    const Vec2 u_dir = rng.uniform2();
    const auto choice = lights_.sample(u_sel);
    if (!choice) return;
    const Light& light = *choice->light;
    const auto le = light.sample_le(u_pos, u_dir);
    if (!le || !(le->pdf_pos > 0) || !(le->pdf_dir > 0)) return;
    const double pdf_emit = choice->pmf * le->pdf_pos;
    std::optional<Hit> on_light;
    if (light.flags() & light_flags::kArea) {
      on_light = scene.sample_area(static_cast<const AreaLight&>(light).shape_id(), u_pos).hit;
      if (on_light->p != le->ray.o)
        throw std::logic_error("photon tracer: AreaLight::sample_le no longer samples Scene::sample_area(u_pos)");
    }
    const bool has_normal = le->n != Vec3(0.0);
    const double cos_emit = has_normal ? std::abs(glm::dot(le->n, le->ray.d)) : 1.0;
    Rgb beta = le->le * (cos_emit / (pdf_emit * le->pdf_dir));
    if (is_black(beta)) return;
    Ray ray = on_light ? spawn_ray(*on_light, le->ray.d) : le->ray;

    for (int depth = 0; depth < st_.max_depth; ++depth) {
      const std::optional<Hit> hit = scene.intersect(ray);
      if (!hit) break;
      const SurfaceInfo& surf = world_.surface(hit->shape_id);
      if (!surf.bsdf) break;
      const SurfaceScatter scatter(*hit, *surf.bsdf);
      const Vec3 wo = -ray.d;
      if (surf.bsdf->flags() & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy))
        out.push_back(Photon{hit->p, wo, beta, depth});
      const double u_lobe = rng.uniform();
      const Vec2 u_bsdf = rng.uniform2();
      const double u_rr = rng.uniform();
      if (depth + 1 >= st_.max_depth) break;  // a photon arriving later could not count
      const auto bs = scatter.sample(wo, u_lobe, u_bsdf, TransportMode::kImportance);
      if (!bs || is_black(bs->weight)) break;
      beta *= bs->weight;
      ray = spawn_ray(*hit, bs->wi);
      if (st_.russian_roulette && depth + 1 >= st_.rr_min_depth) {
        const double q = std::min(1.0, max_component(beta));
        if (!(u_rr < q)) break;
        beta /= q;
      }
    }
  }

 private:
  const World& world_;
  const RenderSettings& st_;
  LightSampler lights_;
};

// One photon map: photons [first, first + n) of the run's photon streams, and the grid over them.
struct PhotonMap {
  std::vector<Photon> photons;
  PointGrid grid;
  int64_t emitted = 0;  // N, the number of light paths traced
};

inline void build_photon_map(const World& world, const RenderSettings& st, uint64_t first, int64_t n,
                             double cell_size, PhotonMap* map) {
  const PhotonTracer tracer(world, st);
  const uint64_t chunks = (static_cast<uint64_t>(n) + kPhotonChunk - 1) / kPhotonChunk;
  std::vector<std::vector<Photon>> parts(chunks);
  parallel_for(chunks, [&](size_t c) {
    const uint64_t begin = c * kPhotonChunk, end = std::min<uint64_t>(static_cast<uint64_t>(n), begin + kPhotonChunk);
    parts[c].reserve((end - begin) * 2);
    for (uint64_t i = begin; i < end; ++i) {
      Rng rng = Rng::for_sample(st.seed, kPhotonKey, first + i);
      tracer.trace(rng, parts[c]);
    }
  });
  size_t total = 0;
  for (const auto& p : parts) total += p.size();
  map->photons.clear();
  map->photons.reserve(total);
  for (const auto& p : parts) map->photons.insert(map->photons.end(), p.begin(), p.end());
  std::vector<Vec3> pos(map->photons.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = map->photons[i].p;
  map->grid.build(pos, cell_size);
  map->emitted = n;
}

// What one camera sample finds: emission seen through delta bounces, and at each non-delta vertex
// the photons within r: their count and their sum of camera throughput x f x beta (unnormalised).
struct GatherResult {
  Rgb emitted{0.0};
  Rgb phi{0.0};
  int64_t count = 0;
};

inline GatherResult gather(const World& world, const RenderSettings& st, const PhotonMap& map, Ray ray, Rgb beta,
                           double radius, Rng& rng) {
  GatherResult g;
  const Scene& scene = world.geometry();
  for (int depth = 0;; ++depth) {
    const std::optional<Hit> hit = scene.intersect(ray);
    if (!hit) {
      for (const Light* env : world.infinite_lights()) g.emitted += beta * env->le(Vec3(0.0), ray.d);
      break;
    }
    const SurfaceInfo& surf = world.surface(hit->shape_id);
    const Vec3 wo = -ray.d;
    if (surf.emitter) g.emitted += beta * surf.emitter->le(hit->n, wo);
    if (!surf.bsdf || depth >= st.max_depth) break;
    const SurfaceScatter scatter(*hit, *surf.bsdf);
    const uint32_t flags = scatter.flags();
    if (flags & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy)) {
      const int max_photon_depth = st.max_depth - 1 - depth;
      map.grid.for_each_within(hit->p, radius, [&](uint32_t k) {
        const Photon& ph = map.photons[k];
        if (ph.depth > max_photon_depth) return;
        const Rgb f = scatter.f(wo, ph.wi, TransportMode::kRadiance);
        if (is_black(f)) return;
        const double cos_g = std::abs(glm::dot(hit->ng, ph.wi));
        if (!(cos_g > 0)) return;
        g.phi += beta * f * ph.beta * (scatter.abs_cos_shading(ph.wi) / cos_g);
        ++g.count;
      });
    }
    const double u_lobe = rng.uniform();
    const Vec2 u_bsdf = rng.uniform2();
    if (!(flags & bsdf_flags::kDelta)) break;
    // Delta lobes continue the path; a non-delta lobe sampled here is what the photons counted.
    const auto bs = scatter.sample(wo, u_lobe, u_bsdf, TransportMode::kRadiance);
    if (!bs || !bs->is_delta() || is_black(bs->weight)) break;
    beta *= bs->weight;
    ray = spawn_ray(*hit, bs->wi);
  }
  return g;
}

template <class Terms>
int64_t render_pm_with(const World& world, const RenderSettings& st, Film& film) {
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  const PhotonMapParams prm = photon_map_params(world, st, film.pixel_count() * spp_pass, false);
  const double area = Terms::kernel_area(prm.radius);
  const Camera& cam = world.camera();
  PhotonMap map;
  return run_passes(st, film, [&](int64_t pass, int64_t spp) {
    build_photon_map(world, st, static_cast<uint64_t>(pass) * static_cast<uint64_t>(prm.photons), prm.photons,
                     prm.radius, &map);
    const double norm = 1.0 / (static_cast<double>(map.emitted) * area);
    for_each_film_tile(film, 16, [&](FilmTile& tile) {
      for_each_camera_sample(tile, film.width(), st, pass, spp, [&](int x, int y, uint64_t index, Rng& rng) {
        const Vec2 film_u = rng.uniform2();
        const Vec2 lens_u = rng.uniform2();
        const Vec2 raster(x + film_u.x, y + film_u.y);
        const CameraPrimaryRay cr = cam.generate_primary_ray(raster, lens_u);
        Rgb v(0.0);
        if (cr.weight > 0) {
          const GatherResult g = gather(world, st, map, cr.ray, Rgb(cr.weight), prm.radius, rng);
          v = g.emitted + g.phi * norm;
        }
        tile.add_sample(raster, v, index);
      });
    });
    return 0.0;
  });
}

// Per-pixel SPPM statistics (Hachisuka & Jensen 2009).
struct SppmPixel {
  double r2 = 0.0;   // current radius squared
  double n = 0.0;    // accumulated photon count N
  Rgb tau{0.0};      // unnormalised flux
  Rgb emitted{0.0};  // sum of the emission seen over the iterations
};

template <class Terms>
int64_t render_sppm_with(const World& world, const RenderSettings& st, Film& film) {
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t iterations = std::max<int64_t>(1, st.spp / passes);
  const PhotonMapParams prm = photon_map_params(world, st, film.pixel_count(), true);
  const Camera& cam = world.camera();
  const int w = film.width(), h = film.height();
  const size_t pixels = static_cast<size_t>(film.pixel_count());
  PhotonMap map;
  std::vector<SppmPixel> px(pixels);
  return for_each_pass_batch(st, passes, 1, [&](int64_t pass, int64_t) {
    std::fill(px.begin(), px.end(), SppmPixel{prm.radius * prm.radius, 0.0, Rgb(0.0), Rgb(0.0)});
    double max_r2 = prm.radius * prm.radius;
    int64_t done = 0;  // iterations done (fewer than `iterations` when interrupted)
    for (int64_t it = 0; it < iterations; ++it) {
      if (st.interrupted && st.interrupted->load()) break;
      ++done;
      const uint64_t iteration = static_cast<uint64_t>(pass * iterations + it);
      build_photon_map(world, st, iteration * static_cast<uint64_t>(prm.photons), prm.photons, std::sqrt(max_r2), &map);
      parallel_for(static_cast<size_t>(h), [&](size_t y) {
        for (int x = 0; x < w; ++x) {
          const uint64_t pixel = y * static_cast<uint64_t>(w) + static_cast<uint64_t>(x);
          SppmPixel& s = px[pixel];
          Rng rng = Rng::for_sample(st.seed, pixel, iteration);
          const Vec2 film_u = rng.uniform2();
          const Vec2 lens_u = rng.uniform2();
          const CameraPrimaryRay cr =
              cam.generate_primary_ray(Vec2(x + film_u.x, static_cast<double>(y) + film_u.y), lens_u);
          if (!(cr.weight > 0)) continue;
          const GatherResult g = gather(world, st, map, cr.ray, Rgb(cr.weight), std::sqrt(s.r2), rng);
          s.emitted += g.emitted;
          if (g.count > 0) {
            const double m = static_cast<double>(g.count);
            const double ratio = (s.n + prm.alpha * m) / (s.n + m);
            s.n += prm.alpha * m;
            s.tau = (s.tau + g.phi) * ratio;
            s.r2 *= ratio;
          }
        }
      });
      max_r2 = 0.0;
      for (const SppmPixel& s : px) max_r2 = std::max(max_r2, s.r2);
    }
    if (done == 0) return;
    const double emitted_total = static_cast<double>(done) * static_cast<double>(prm.photons);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const SppmPixel& s = px[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
        const Rgb v = s.emitted * (1.0 / static_cast<double>(done)) +
                      s.tau * (1.0 / (emitted_total * Terms::kernel_area(std::sqrt(s.r2))));
        film.add_sample(Vec2(x + 0.5, y + 0.5), v, static_cast<uint64_t>(pass));
      }
    film.end_pass(0.0);
  });
}

}  // namespace detail
}  // namespace tb

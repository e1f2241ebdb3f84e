// The path tracer as a template over the estimator's terms (estimator_terms.h): path_tracer.cpp
// instantiates ExactTerms for render_pt and pt_sample; the negative controls of validate/
// instantiate broken terms. The algorithm is documented in path_tracer.h.
#pragma once

#include <array>
#include <atomic>
#include <limits>
#include <vector>

#include "estimators/mis_heuristics.h"
#include "lib/core/rng.h"
#include "lib/core/sample_dims.h"
#include "lib/core/uniforms.h"
#include "lib/differential/variance_bound.h"
#include "lib/film/film_parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/estimator_terms.h"
#include "lib/integrator/pass_loop.h"
#include "lib/integrator/path_tracer.h"
#include "lib/path/light_sampler.h"
#include "lib/path/scattering.h"
#include "lib/material/half_vector.h"

namespace tb::detail {

// The power heuristic with beta = 2 (Veach Eq. 9.13) for the two techniques at a vertex, both
// densities in solid angle at the vertex: the two-technique form of PowerHeuristic (two divisions
// instead of four; equal up to rounding).
inline double mis2(double p_this, double p_other) { return power_heuristic_2(p_this, p_other); }

struct BounceUniforms {
  std::array<double, kDimsPerBounce> u;
  template <class U>
  explicit BounceUniforms(U& src) {
    for (double& v : u) v = src.next();
  }
  double operator[](BounceDim d) const { return u[static_cast<size_t>(d)]; }
};

// Records a path tracer's contributions one path at a time with their variance-bounding ratios
// (pt_sample_paths in path_tracer.h): r_emit applies to emission found at the current vertex,
// r_nee to its next-event connection.
struct PathRecorder {
  std::vector<PathContribution>* out = nullptr;
  double camera_density = 0.0;  // p(i_1) per unit raster area
  double r_emit = 1.0, r_nee = 1.0;
  double compression = 1.0;     // |di_m / di_1|
  void add(const Rgb& v, double r) const {
    if (!is_black(v)) out->push_back({v, r});
  }
  // After the BSDF sample at a vertex: its term joins the sums of the vertices beyond.
  void bounce(const SurfacePoint& hit, const Bsdf& bsdf, const Vec3& wo, const Vec3& wi, double pdf, bool delta,
              bool transmission) {
    if (transmission) {
      const double eta_b = bsdf.eta();
      const double eta = glm::dot(wo, hit.n) > 0 ? eta_b : 1.0 / eta_b;  // eta_wi_side / eta_wo_side
      Vec3 m = generalized_half_vector(wi, wo, eta, 1.0);
      if (glm::dot(m, wo) < 0) m = -m;
      compression *= differential::refraction_solid_angle_ratio(wo, wi, m, eta);
    }
    r_emit = r_nee;
    if (delta) return;
    const double term = pdf > 0.0 && compression > 0.0 ? camera_density / (pdf * compression)
                                                       : std::numeric_limits<double>::infinity();
    r_nee += term;
  }
};

template <class Terms>
class PathTracer {
 public:
  PathTracer(const World& world, const RenderSettings& st, const LightSampler& lights)
      : world_(world), st_(st), lights_(lights) {}

  // Radiance arriving along the camera ray (Veach Eq. 3.7 estimated by the path integral,
  // pbrt-v3 PathIntegrator::Li). U is Uniforms or a final class derived from it (RngUniforms in
  // the render loop), so that next() is a direct, inlined call there. Vertices are lean
  // SurfacePoints: the path tracer never needs the derivatives of a Hit.
  // With `rec`, every contribution is also recorded as its own path (pt_sample_paths).
  // With skip_first_emission, emission found by the ray itself (its first hit, or the environment
  // when it misses) is left out: the caller weights it (pf1, path_filter_impl.h).
  template <class U>
  Rgb li(Ray ray, U& rng, RayCounts& counts, PathRecorder* rec = nullptr, bool skip_first_emission = false) const {
    const Scene& scene = world_.geometry();
    Rgb L(0.0), beta(1.0);
    bool count_emission_fully = true;  // camera ray, or the last bounce was a delta lobe
    double prev_pdf_bsdf = 0.0;        // solid angle, of the last BSDF sample
    Vec3 prev_p(0.0);                  // the vertex the ray left
    SurfacePoint hit;                  // the current vertex (one record per path, see intersect_point)
    for (int depth = 0;; ++depth) {
      ++counts.extension;
      if (!scene.intersect_point(ray, &hit)) {
        if (depth == 0 && skip_first_emission) break;
        for (const Light* env : world_.infinite_lights()) {
          const Rgb le = env->le(Vec3(0.0), ray.d);
          if (is_black(le)) continue;
          const Rgb c = beta * le * emission_weight(count_emission_fully, prev_pdf_bsdf, env, prev_p, ray.d, nullptr);
          L += c;
          if (rec) rec->add(c, rec->r_emit);
        }
        break;
      }
      const SurfaceInfo& surf = world_.surface(hit.shape_id);
      const Vec3 wo = -ray.d;
      if (surf.emitter && !(depth == 0 && skip_first_emission)) {
        const Rgb le = surf.emitter->le(hit.n, wo);
        if (!is_black(le)) {
          const Rgb c = beta * le * emission_weight(count_emission_fully, prev_pdf_bsdf, surf.emitter, prev_p, ray.d, &hit);
          L += c;
          if (rec) rec->add(c, rec->r_emit);
        }
      }
      if (!surf.bsdf || depth >= st_.max_depth) break;
      const SurfaceScatter scatter(hit, *surf.bsdf);
      const BounceUniforms u(rng);

      // Next-event estimation (Veach Eq. 9.12 with the light technique's weight).
      if (scatter.flags() & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy)) {
        const Rgb c = beta * direct(scatter, wo, u, counts);
        L += c;
        if (rec) rec->add(c, rec->r_nee);
      }

      // BSDF sampling: extends the path and, when it hits an emitter, is the second technique.
      const auto bs = scatter.sample(wo, u[BounceDim::kBsdfLobe], {u[BounceDim::kBsdfU], u[BounceDim::kBsdfV]},
                                     TransportMode::kRadiance);
      if (!bs || is_black(bs->weight)) break;
      if (rec)
        rec->bounce(hit, *surf.bsdf, wo, bs->wi, bs->pdf, bs->is_delta(),
                    glm::dot(wo, hit.ng) * glm::dot(bs->wi, hit.ng) < 0.0);
      beta *= bs->weight;
      count_emission_fully = bs->is_delta();
      prev_pdf_bsdf = bs->pdf;
      prev_p = hit.p;
      spawn_ray_into(hit, bs->wi, &ray);

      if (st_.russian_roulette && depth + 1 >= st_.rr_min_depth) {
        const double q = std::min(1.0, max_component(beta));
        if (!(u[BounceDim::kRussianRoulette] < q)) break;
        if constexpr (Terms::kRouletteDividesByQ) beta /= q;
      }
    }
    return L;
  }

 private:
  // MIS weight of emission found by BSDF sampling (or by the camera ray): the light technique
  // would have sampled the same direction with density pmf * pdf_li (solid angle at prev_p).
  double emission_weight(bool fully, double pdf_bsdf, const Light* light, const Vec3& prev_p, const Vec3& wi,
                         const SurfacePoint* on_light) const {
    if (fully) return 1.0;
    if constexpr (!Terms::kMisFullDenominator) return 1.0;  // light density left out
    const double pdf_light = lights_.pmf(light) * light->pdf_li(prev_p, wi, on_light);
    return mis2(pdf_bsdf, pdf_light);
  }

  // Light sample: f L |cos| / (pmf pdf_li), weighted against the BSDF technique.
  Rgb direct(const SurfaceScatter& scatter, const Vec3& wo, const BounceUniforms& u, RayCounts& counts) const {
    const auto choice = lights_.sample(u[BounceDim::kLightSelect]);
    if (!choice) return Rgb(0.0);
    const SurfacePoint& hit = scatter.hit();
    const auto ls = choice->light->sample_li_point(hit.p, {u[BounceDim::kLightU], u[BounceDim::kLightV]});
    if (!ls || !(ls->pdf > 0) || is_black(ls->li)) return Rgb(0.0);
    double pdf_bsdf = 0.0;  // the BSDF technique's density of ls->wi, for the MIS weight
    const Rgb f = scatter.f_pdf(wo, ls->wi, TransportMode::kRadiance, &pdf_bsdf);
    if (is_black(f)) return Rgb(0.0);
    const double cos_i = Terms::kNeeReceiverCosine ? scatter.abs_cos_shading(ls->wi) : 1.0;
    ++counts.shadow;
    const bool blocked = std::isinf(ls->distance) ? world_.geometry().occluded(spawn_ray(hit, ls->wi))
                                                  : world_.geometry().occluded(spawn_ray_to(hit, ls->p_light));
    if (blocked) return Rgb(0.0);
    const double pdf_light = choice->pmf * ls->pdf;
    const double w = choice->light->is_delta() ? 1.0 : mis2(pdf_light, pdf_bsdf);
    return f * ls->li * (cos_i * w / pdf_light);
  }

  const World& world_;
  const RenderSettings& st_;
  const LightSampler& lights_;
};


template <class Terms>
Rgb pt_sample_with(const PathContext& ctx, const RenderSettings& st, const Vec2& raster, Uniforms& u) {
  const PathTracer<Terms> pt(*ctx.world, st, *ctx.lights);
  const Vec2 lens_u = u.next2();  // CameraDim::kLensU, kLensV
  const CameraPrimaryRay cr = ctx.world->camera().generate_primary_ray(raster, lens_u);
  if (!(cr.weight > 0)) return Rgb(0.0);
  RayCounts rc;
  return cr.weight * pt.li(cr.ray, u, rc);
}

template <class Terms>
void pt_sample_paths_with(const PathContext& ctx, const RenderSettings& st, const Vec2& raster, Uniforms& u,
                          std::vector<PathContribution>* out) {
  const PathTracer<Terms> pt(*ctx.world, st, *ctx.lights);
  const Vec2 lens_u = u.next2();  // CameraDim::kLensU, kLensV
  const Camera& cam = ctx.world->camera();
  const CameraPrimaryRay cr = cam.generate_primary_ray(raster, lens_u);
  if (!(cr.weight > 0)) return;
  const size_t first = out->size();
  PathRecorder rec;
  rec.out = out;
  rec.camera_density = cam.pdf_we(cr.ray).dir * static_cast<double>(cam.pixel_count());
  RayCounts rc;
  pt.li(cr.ray, u, rc, &rec);
  for (size_t i = first; i < out->size(); ++i) (*out)[i].value *= cr.weight;
}

template <class Terms>
int64_t render_pt_with(const World& world, const RenderSettings& st, Film& film, RayCounts* counts) {
  const LightSampler lights(world);
  const PathTracer<Terms> pt(world, st, lights);
  const Camera& cam = world.camera();
  std::atomic<int64_t> n_ext{0}, n_shadow{0};
  const int64_t done = run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    for_each_film_tile(film, 16, [&](FilmTile& tile) {
      RayCounts rc;
      for_each_camera_sample(tile, film.width(), st, pass, spp_pass, [&](int x, int y, uint64_t index, Rng& stream) {
        RngUniforms rng(stream);
        const Vec2 film_u = rng.next2();  // CameraDim::kFilmX, kFilmY
        const Vec2 lens_u = rng.next2();  // CameraDim::kLensU, kLensV
        const Vec2 raster(x + film_u.x, y + film_u.y);
        const CameraPrimaryRay cr = cam.generate_primary_ray(raster, lens_u);
        const Rgb v = cr.weight > 0 ? cr.weight * pt.li(cr.ray, rng, rc) : Rgb(0.0);
        tile.add_sample(raster, v, index);
      });
      n_ext.fetch_add(rc.extension, std::memory_order_relaxed);
      n_shadow.fetch_add(rc.shadow, std::memory_order_relaxed);
    });
    return 0.0;
  });
  if (counts) {
    counts->extension += n_ext.load();
    counts->shadow += n_shadow.load();
  }
  return done;
}

}  // namespace tb::detail

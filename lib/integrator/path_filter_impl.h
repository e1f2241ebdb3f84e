// pf1 as a template over its weighting (Pf1ExactWeights in path_filter.h; the negative controls of
// validate/render/broken_path_filter.h instantiate broken ones). The estimator is documented in
// path_filter.h and docs/mmis-paths.md.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <span>
#include <vector>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/core/uniforms.h"
#include "lib/film/film_parallel.h"
#include "lib/geometry/spawn.h"
#include "lib/integrator/estimator_terms.h"
#include "lib/integrator/pass_loop.h"
#include "lib/integrator/path_filter.h"
#include "lib/integrator/path_tracer_impl.h"
#include "lib/integrator/photon_map.h"
#include "lib/path/light_sampler.h"
#include "lib/path/scattering.h"

namespace tb::detail {

// One camera prefix of a pass (Sec. 5: the auxiliary vertices of a conditional technique).
struct Pf1Prefix {
  SurfacePoint hit;      // x_1 (filterable prefixes only)
  Vec3 wo{0.0};          // towards the camera
  Vec3 wi{0.0};          // the direction sampled at x_1 (has_dir)
  double cam_weight = 0;
  Vec2 raster{0.0};
  Rgb value{0.0};        // emission seen at x_1 (filterable) or the whole path-tracer sample (not)
  bool filterable = false;
  bool has_dir = false;
  // The query's light sample at x_1 (next-event estimation, a classical technique, Sec. 3.1):
  // direction, f |cos| at x_1, unoccluded radiance, solid-angle density pmf * pdf_li.
  bool has_light = false, light_delta = false;
  Vec3 wl{0.0};
  Rgb f_light{0.0}, li_light{0.0};
  double pdf_light = 0.0;
};

struct Pf1Pass {
  std::vector<Pf1Prefix> prefixes;  // by slot = pixel * spp_pass + s
  std::vector<uint32_t> filterable;  // slots of the filterable prefixes (grid point k -> slot)
  PointGrid grid;
};

inline bool pf1_filterable(uint32_t flags) {
  return !(flags & bsdf_flags::kDelta) && (flags & (bsdf_flags::kDiffuse | bsdf_flags::kGlossy));
}

// The prefixes of pass `pass` (spp_pass per pixel) and the grid over their first vertices.
inline void pf1_trace_prefixes(const World& world, const RenderSettings& st, const PathTracer<ExactTerms>& pt,
                               const LightSampler& lights, int64_t pass, int64_t spp_pass, double radius,
                               Pf1Pass* out) {
  const Camera& cam = world.camera();
  const Scene& scene = world.geometry();
  const size_t pixels = static_cast<size_t>(cam.pixel_count());
  const int width = cam.width();
  out->prefixes.assign(pixels * static_cast<size_t>(spp_pass), Pf1Prefix{});
  parallel_for(pixels, [&](size_t pixel) {
    RayCounts rc;
    for (int64_t s = 0; s < spp_pass; ++s) {
      Pf1Prefix& pr = out->prefixes[pixel * static_cast<size_t>(spp_pass) + static_cast<size_t>(s)];
      Rng stream = Rng::for_sample(st.seed, pixel, static_cast<uint64_t>(pass * spp_pass + s));
      RngUniforms rng(stream);
      const Vec2 film_u = rng.next2();  // CameraDim::kFilmX, kFilmY
      const Vec2 lens_u = rng.next2();  // CameraDim::kLensU, kLensV
      pr.raster = Vec2(static_cast<double>(pixel % static_cast<size_t>(width)) + film_u.x,
                       static_cast<double>(pixel / static_cast<size_t>(width)) + film_u.y);
      const CameraPrimaryRay cr = cam.generate_primary_ray(pr.raster, lens_u);
      if (!(cr.weight > 0)) continue;
      pr.cam_weight = cr.weight;
      SurfacePoint hit;
      bool filterable = st.max_depth >= 1 && scene.intersect_point(cr.ray, &hit);
      const SurfaceInfo* surf = filterable ? &world.surface(hit.shape_id) : nullptr;
      filterable = filterable && surf->bsdf && pf1_filterable(surf->bsdf->flags());
      if (!filterable) {  // a plain path-tracer sample, the same uniforms after the lens
        pr.value = cr.weight * pt.li(cr.ray, rng, rc);
        continue;
      }
      pr.filterable = true;
      pr.hit = hit;
      pr.wo = -cr.ray.d;
      if (surf->emitter) pr.value = cr.weight * surf->emitter->le(hit.n, pr.wo);  // seen by the camera: weight 1
      const BounceUniforms u(rng);
      const SurfaceScatter scatter(pr.hit, *surf->bsdf);
      const auto bs = scatter.sample(pr.wo, u[BounceDim::kBsdfLobe], {u[BounceDim::kBsdfU], u[BounceDim::kBsdfV]},
                                     TransportMode::kRadiance);
      // Kept even where f at y_j is 0 (e.g. below the geometric surface of a shading-normal frame): the
      // technique's density p_j, which every denominator evaluates with SurfaceScatter::pdf, includes them.
      if (bs && !bs->is_delta() && bs->pdf > 0) {
        pr.wi = bs->wi;
        pr.has_dir = true;
      }
      // Next-event estimation at x_1 with the query's own uniforms (as the path tracer draws them).
      if (const auto choice = lights.sample(u[BounceDim::kLightSelect])) {
        const auto ls = choice->light->sample_li_point(pr.hit.p, {u[BounceDim::kLightU], u[BounceDim::kLightV]});
        if (ls && ls->pdf > 0 && !is_black(ls->li)) {
          const Rgb f = scatter.f(pr.wo, ls->wi, TransportMode::kRadiance) * scatter.abs_cos_shading(ls->wi);
          const bool blocked = is_black(f) || (std::isinf(ls->distance) ? scene.occluded(spawn_ray(pr.hit, ls->wi))
                                                                         : scene.occluded(spawn_ray_to(pr.hit, ls->p_light)));
          if (!blocked) {
            pr.has_light = true;
            pr.light_delta = choice->light->is_delta();
            pr.wl = ls->wi;
            pr.f_light = f;
            pr.li_light = ls->li;
            pr.pdf_light = choice->pmf * ls->pdf;
          }
        }
      }
    }
  });
  out->filterable.clear();
  std::vector<Vec3> pos;
  for (size_t slot = 0; slot < out->prefixes.size(); ++slot)
    if (out->prefixes[slot].filterable) {
      out->filterable.push_back(static_cast<uint32_t>(slot));
      pos.push_back(out->prefixes[slot].hit.p);
    }
  out->grid.build(pos, radius);
}

// The kernel around x over the points of `grid` (grid point k -> slot filterable[k], positions pos(slot)):
// member slots within radius r, at most max_members of them (the nearest, ties by slot; `self`, when one
// of the points, always kept: distance -1), sorted by slot. A function of the positions only.
template <class Pos>
void filter_kernel(const PointGrid& grid, std::span<const uint32_t> filterable, const Pos& pos, const Vec3& x,
                   uint32_t self, const Pf1Params& prm, std::vector<uint32_t>* members) {
  struct Near {
    double d2;
    uint32_t slot;
  };
  std::vector<Near> found;
  grid.for_each_within(x, prm.radius, [&](uint32_t k) {
    const uint32_t s = filterable[k];
    const Vec3 d = pos(s) - x;
    found.push_back({s == self ? -1.0 : glm::dot(d, d), s});
  });
  if (static_cast<int>(found.size()) > prm.max_members) {
    std::sort(found.begin(), found.end(),
              [](const Near& a, const Near& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.slot < b.slot); });
    found.resize(static_cast<size_t>(prm.max_members));
  }
  members->clear();
  for (const Near& n : found) members->push_back(n.slot);
  std::sort(members->begin(), members->end());
}

// The kernel of the query in `slot`: member slots (the query always kept, then sorted by slot) and the
// query's position among them.
inline int pf1_kernel(const Pf1Pass& pass, uint32_t slot, const Pf1Params& prm, std::vector<uint32_t>* members) {
  filter_kernel(pass.grid, pass.filterable, [&](uint32_t s) { return pass.prefixes[s].hit.p; },
                pass.prefixes[slot].hit.p, slot, prm, members);
  return static_cast<int>(std::lower_bound(members->begin(), members->end(), slot) - members->begin());
}

// pdf[j * m + k] = p_j(w_k): member j's BSDF density (for its own wo) of member k's direction; with
// `light`, row j also gets p_j(w_light) of the query's light sample at column m (row stride m + 1).
inline void pf1_kernel_pdfs(const World& world, const Pf1Pass& pass, const std::vector<uint32_t>& members,
                            std::vector<double>* pdf, const Vec3* light = nullptr) {
  const size_t m = members.size();
  const size_t stride = light ? m + 1 : m;
  pdf->assign(m * stride, 0.0);
  for (size_t j = 0; j < m; ++j) {
    const Pf1Prefix& pj = pass.prefixes[members[j]];
    const SurfaceScatter sj(pj.hit, *world.surface(pj.hit.shape_id).bsdf);
    for (size_t k = 0; k < m; ++k) {
      const Pf1Prefix& pk = pass.prefixes[members[k]];
      if (pk.has_dir) (*pdf)[j * stride + k] = sj.pdf(pj.wo, pk.wi, TransportMode::kRadiance);
    }
    if (light) (*pdf)[j * stride + m] = sj.pdf(pj.wo, *light, TransportMode::kRadiance);
  }
}

struct Pf1Stats {
  double prefix_seconds = 0, filter_seconds = 0;
  int64_t queries = 0, members = 0, passes = 0;
};
void pf1_store_timing(const Pf1Stats& s);  // path_filter.cpp

// Emission found by a filtered direction w leaving the vertex at `from` (hit: the surface the ray
// reached, null when it missed): calls emit(le, pl) for the emitter there (or every infinite light on a
// miss) with the radiance le towards `from` and pl = pmf * pdf_li, the solid-angle density with which
// the light sample at `from` would have chosen w (its classical term, as pt's emission weight).
template <class Emit>
void for_each_filtered_emission(const World& world, const LightSampler& lights, const SurfacePoint& from,
                                const Vec3& w, const SurfacePoint* hit, Emit&& emit) {
  if (hit) {
    const SurfaceInfo& s2 = world.surface(hit->shape_id);
    if (!s2.emitter) return;
    const Rgb le = s2.emitter->le(hit->n, -w);
    if (is_black(le)) return;
    emit(le, lights.pmf(s2.emitter) * s2.emitter->pdf_li(from.p, w, hit));
    return;
  }
  for (const Light* env : world.infinite_lights()) {
    const Rgb le = env->le(Vec3(0.0), w);
    if (is_black(le)) continue;
    emit(le, lights.pmf(env) * env->pdf_li(from.p, w, nullptr));
  }
}

// pf1's continuation beyond x_2: a fresh path-tracer estimate of the light scattered at x_2 and beyond.
struct Pf1Suffix {
  const PathTracer<ExactTerms>& suffix;
  void begin_pass(int64_t /*pass*/, int64_t /*spp_pass*/, const Pf1Pass& /*pass1*/) {}
  // f = f_i(w_k) |cos| at x_1; w = member k's level-1 weight (column, own k); returns the contribution
  // to the query's sum (before the camera weight).
  Rgb scattered(uint32_t /*query_slot*/, const Ray& ray, const SurfacePoint* /*hit2*/, const Rgb& f,
                std::span<const double> /*column*/, int /*k*/, int /*query*/, const FilteringWeight& w,
                RngUniforms& rng, RayCounts& rc) const {
    const Rgb L = suffix.li(ray, rng, rc, nullptr, true);
    return f * L * (w.weight / w.own_pdf);  // = f L / D(w_k) for the exact weights
  }
};

// The filtering renderer: level 1 (the first camera vertex) as pf1; `cont` continues every member's
// output path beyond x_2 (pf1: Pf1Suffix; pfk: the further filtered vertices, path_filter_multi_impl.h).
template <class Weights, class Continuation>
int64_t render_path_filter_with(const World& world, const RenderSettings& st, Film& film, const Pf1Params& prm,
                                const LightSampler& lights, Continuation& cont) {
  const PathTracer<ExactTerms> pt(world, st, lights);
  Pf1Pass pass_data;
  Pf1Stats stats;
  std::atomic<int64_t> queries{0}, members_total{0};
  using clock = std::chrono::steady_clock;
  const int64_t done = run_passes(st, film, [&](int64_t pass, int64_t spp_pass) {
    const auto t0 = clock::now();
    pf1_trace_prefixes(world, st, pt, lights, pass, spp_pass, prm.radius, &pass_data);
    cont.begin_pass(pass, spp_pass, pass_data);
    const auto t1 = clock::now();
    const uint64_t pair_seed = hash_values(st.seed, hash_string("pf1"), static_cast<uint64_t>(pass));
    for_each_film_tile(film, 16, [&](FilmTile& tile) {
      std::vector<uint32_t> members;
      std::vector<double> pdf, column;
      RayCounts rc;
      int64_t nq = 0, nm = 0;
      for_each_camera_sample(tile, film.width(), st, pass, spp_pass, [&](int x, int y, uint64_t index, Rng&) {
        const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(film.width()) + static_cast<uint64_t>(x);
        const uint32_t slot = static_cast<uint32_t>(pixel * static_cast<uint64_t>(spp_pass) +
                                                    (index - static_cast<uint64_t>(pass * spp_pass)));
        const Pf1Prefix& q = pass_data.prefixes[slot];
        Rgb v = q.value;
        if (q.filterable) {
          const int qpos = pf1_kernel(pass_data, slot, prm, &members);
          const int m = static_cast<int>(members.size());
          ++nq;
          nm += m;
          const bool nee = q.has_light && !q.light_delta;
          pf1_kernel_pdfs(world, pass_data, members, &pdf, nee ? &q.wl : nullptr);
          const size_t stride = nee ? members.size() + 1 : members.size();
          const SurfaceScatter sq(q.hit, *world.surface(q.hit.shape_id).bsdf);
          column.resize(members.size());
          Rgb sum(0.0);
          // The light sample: a delta light only it can sample (weight 1); otherwise balance over
          // itself (the classical term, Sec. 3.1 split) and every member's conditional density.
          if (q.has_light && q.light_delta) sum += q.f_light * q.li_light / q.pdf_light;
          if (nee) {
            for (int j = 0; j < m; ++j) column[j] = pdf[static_cast<size_t>(j) * stride + static_cast<size_t>(m)];
            const FilteringWeight w = Weights::weight(column, -1, qpos, q.pdf_light);
            sum += q.f_light * q.li_light * safe_ratio(1.0, w.denominator);
          }
          for (int k = 0; k < m; ++k) {
            const Pf1Prefix& pk = pass_data.prefixes[members[k]];
            if (!pk.has_dir) continue;
            for (int j = 0; j < m; ++j) column[j] = pdf[static_cast<size_t>(j) * stride + static_cast<size_t>(k)];
            const FilteringWeight w = Weights::weight(column, k, qpos, 0.0);
            if (!(w.own_pdf > 0)) continue;
            // f at the query vertex along the actual connection (Sec. 5.1, unbiased variant).
            const Rgb f = sq.f(q.wo, pk.wi, TransportMode::kRadiance) * sq.abs_cos_shading(pk.wi);
            if (is_black(f)) continue;
            Ray ray;
            spawn_ray_into(q.hit, pk.wi, &ray);
            // Emission at x_2 (or the environment): the query's light sample could have found it too,
            // so its denominator adds the classical term pmf * pdf_li (as pt's emission weight does).
            SurfacePoint hit2;
            ++rc.extension;
            const bool found = world.geometry().intersect_point(ray, &hit2);
            for_each_filtered_emission(world, lights, q.hit, pk.wi, found ? &hit2 : nullptr,
                                       [&](const Rgb& le, double pl) {
                                         const FilteringWeight wd = Weights::weight(column, k, qpos, pl);
                                         sum += f * le * (wd.weight / wd.own_pdf);
                                       });
            // The rest (light scattered at x_2 and beyond): only the members sample it. Its own stream
            // per pair (query, member).
            Rng stream = Rng::for_sample(pair_seed, slot, members[k]);
            RngUniforms rng(stream);
            sum += cont.scattered(slot, ray, found ? &hit2 : nullptr, f, column, k, qpos, w, rng, rc);
          }
          v += q.cam_weight * sum;
        }
        tile.add_sample(q.raster, v, index);
      });
      queries.fetch_add(nq, std::memory_order_relaxed);
      members_total.fetch_add(nm, std::memory_order_relaxed);
    });
    const auto t2 = clock::now();
    stats.prefix_seconds += std::chrono::duration<double>(t1 - t0).count();
    stats.filter_seconds += std::chrono::duration<double>(t2 - t1).count();
    ++stats.passes;
    return 0.0;
  });
  stats.queries = queries.load();
  stats.members = members_total.load();
  pf1_store_timing(stats);
  return done;
}

template <class Weights>
int64_t render_pf1_with(const World& world, const RenderSettings& st, Film& film) {
  const Pf1Params prm = pf1_params(world, st);
  const LightSampler lights(world);
  // The suffix from x_2 on: one scattering event (at x_1) already used.
  RenderSettings suffix_st = st;
  suffix_st.max_depth = st.max_depth - 1;
  suffix_st.rr_min_depth = std::max(0, st.rr_min_depth - 1);
  const PathTracer<ExactTerms> suffix(world, suffix_st, lights);
  Pf1Suffix cont{suffix};
  return render_path_filter_with<Weights>(world, st, film, prm, lights, cont);
}

}  // namespace tb::detail

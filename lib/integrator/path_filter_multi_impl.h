// pfk as a template over its weighting (PfkExactWeights in path_filter_multi.h; the negative controls of
// validate/render/broken_path_filter.h instantiate broken ones). Level 1 is pf1's renderer
// (render_path_filter_with, path_filter_impl.h); PfkContinuation filters x_2 .. x_K. The estimator is
// documented in path_filter_multi.h and docs/mmis-paths.md.
#pragma once

#include <algorithm>
#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "lib/integrator/path_filter_impl.h"
#include "lib/integrator/path_filter_multi.h"

namespace tb::detail {

// The depth-d vertices of a pass's prefixes (d >= 2), by slot, and the grid over the filterable ones.
struct PfkDepth {
  std::vector<PfkPassVertex> vertex;  // by slot; hit valid where `filterable`
  std::vector<uint8_t> filterable_flag;
  std::vector<uint32_t> filterable;   // grid point k -> slot
  PointGrid grid;
};

// Output paths recorded for the checks (pfk_sample_paths): only for the queries `record_slots` holds.
struct PfkRecorder {
  std::vector<uint8_t> record_slots;
  std::vector<PfkPassVertex> depth1;  // the filterable first vertices of the recorded pass
  std::mutex mutex;
  std::vector<PfkSampledPath> paths;
};

// 1 / D, 0 for D = 0 (no technique can produce the path: only under a broken weighting, whose images
// must stay finite to be compared).
inline double inverse_or_zero(double d) { return d > 0 ? 1.0 / d : 0.0; }

// One filtered vertex of the output path being built (its column owned here; PfkLevel views it).
struct PfkLevelState {
  SurfacePoint x;
  Vec3 wo{0.0}, w{0.0};
  std::vector<double> column;
  int own = -1, self = -1;
};

template <class Weights>
class PfkContinuation {
 public:
  PfkContinuation(const World& world, const RenderSettings& st, const PfkParams& prm, const LightSampler& lights,
                  PfkRecorder* recorder = nullptr)
      : world_(world), st_(st), prm_(prm), lights_(lights), recorder_(recorder) {
    depths_ = std::min(prm.vertices, st.max_depth);
    // suffix_[d]: the path tracer after d scattering events (at x_1 .. x_d).
    for (int d = 0; d <= std::max(1, depths_); ++d) {
      RenderSettings& s = suffix_settings_.emplace_back(st);  // the path tracer keeps a reference
      s.max_depth = std::max(0, st.max_depth - d);
      s.rr_min_depth = std::max(0, st.rr_min_depth - d);
      suffix_.push_back(std::make_unique<PathTracer<ExactTerms>>(world, s, lights));
    }
  }

  int depths() const { return depths_; }
  const std::vector<PfkDepth>& depth_data() const { return depth_; }

  // The prefixes continued from x_1 to depth K (Sec. 5: the auxiliary vertices of the deeper kernels).
  void begin_pass(int64_t pass, int64_t spp_pass, const Pf1Pass& pass1) {
    (void)spp_pass;
    pass1_ = &pass1;
    const size_t slots = pass1.prefixes.size();
    if (recorder_) {
      recorder_->depth1.clear();
      for (uint32_t s : pass1.filterable) {
        const Pf1Prefix& p = pass1.prefixes[s];
        recorder_->depth1.push_back({p.hit, p.wo, p.wi, p.has_dir, s});
      }
    }
    depth_.resize(static_cast<size_t>(std::max(0, depths_ - 1)));
    for (PfkDepth& dd : depth_) {
      dd.vertex.assign(slots, PfkPassVertex{});
      dd.filterable_flag.assign(slots, 0);
    }
    if (depths_ < 2) return;
    const uint64_t prefix_seed = hash_values(st_.seed, hash_string("pfk.prefix"), static_cast<uint64_t>(pass));
    const Scene& scene = world_.geometry();
    parallel_for(slots, [&](size_t slot) {
      const Pf1Prefix& p1 = pass1.prefixes[slot];
      if (!p1.filterable || !p1.has_dir) return;
      Rng stream = Rng::for_sample(prefix_seed, slot, 0);
      RngUniforms rng(stream);
      SurfacePoint cur = p1.hit;
      Vec3 w = p1.wi;
      for (int d = 2; d <= depths_; ++d) {
        const Ray ray = spawn_ray(cur, w);
        SurfacePoint hit;
        if (!scene.intersect_point(ray, &hit)) break;
        const SurfaceInfo& surf = world_.surface(hit.shape_id);
        if (!surf.bsdf || !pf1_filterable(surf.bsdf->flags())) break;
        PfkDepth& dd = depth_[static_cast<size_t>(d - 2)];
        PfkPassVertex& v = dd.vertex[slot];
        dd.filterable_flag[slot] = 1;
        v.hit = hit;
        v.wo = -ray.d;
        v.slot = static_cast<uint32_t>(slot);
        const BounceUniforms u(rng);
        const SurfaceScatter scatter(hit, *surf.bsdf);
        const auto bs = scatter.sample(v.wo, u[BounceDim::kBsdfLobe], {u[BounceDim::kBsdfU], u[BounceDim::kBsdfV]},
                                       TransportMode::kRadiance);
        if (!bs || bs->is_delta() || !(bs->pdf > 0)) break;
        v.wi = bs->wi;
        v.has_dir = true;
        cur = hit;
        w = bs->wi;
      }
    });
    for (PfkDepth& dd : depth_) {
      dd.filterable.clear();
      std::vector<Vec3> pos;
      for (size_t slot = 0; slot < slots; ++slot)
        if (dd.filterable_flag[slot]) {
          dd.filterable.push_back(static_cast<uint32_t>(slot));
          pos.push_back(dd.vertex[slot].hit.p);
        }
      dd.grid.build(pos, prm_.kernel.radius);
    }
  }

  // The output path of (query, level-1 member k) beyond x_1: filtered at x_2 .. x_K, then the path tracer.
  // f = f_i(w_k) |cos| at x_1, column1 / k / query / w1: its level-1 column and weight (pf1's).
  Rgb scattered(uint32_t query_slot, const Ray& ray1, const SurfacePoint* hit2, const Rgb& f,
                std::span<const double> column1, int k, int query, const FilteringWeight& w1, RngUniforms& rng,
                RayCounts& rc) const {
    const bool record = recorder_ && recorder_->record_slots[query_slot];
    if (recorder_ && !record) return Rgb(0.0);
    if (depths_ < 2) {  // pf1 exactly
      const Rgb L = suffix_[1]->li(ray1, rng, rc, nullptr, true);
      return f * L * (w1.weight / w1.own_pdf);
    }
    if (!hit2) return Rgb(0.0);  // a miss: its emission was weighted at level 1, nothing scatters
    std::vector<PfkLevelState> path(1);
    path[0].column.assign(column1.begin(), column1.end());
    path[0].own = k;
    path[0].self = query;
    path[0].w = ray1.d;
    path[0].x = pass1_->prefixes[query_slot].hit;
    path[0].wo = pass1_->prefixes[query_slot].wo;
    std::vector<PfkLevel> view;
    // The whole path's weight over the levels in `path` (the last column as it stands).
    const auto weigh = [&](bool light_entry, bool delta_light) {
      view.clear();
      for (const PfkLevelState& l : path) view.push_back({l.column, l.own, l.self});
      const FilteringWeight w = Weights::path_weight(view);
      if (record) {
        PfkSampledPath rec;
        rec.query_slot = query_slot;
        for (const PfkLevelState& l : path) rec.levels.push_back({l.x, l.wo, l.w, l.column, l.own, l.self});
        rec.light_entry = light_entry;
        rec.delta_light = delta_light;
        rec.weight = w;
        std::lock_guard<std::mutex> lock(recorder_->mutex);
        recorder_->paths.push_back(std::move(rec));
      }
      return w;
    };
    const Scene& scene = world_.geometry();
    Rgb out(0.0), beta = f;
    Ray ray = ray1;
    SurfacePoint x = *hit2;
    int scattered_at = 1;  // scattering events of the output path so far
    std::vector<uint32_t> members;
    for (int d = 2; d <= depths_; ++d) {
      const SurfaceInfo& surf = world_.surface(x.shape_id);
      if (!surf.bsdf || !pf1_filterable(surf.bsdf->flags())) break;  // the path tracer goes on from here
      const PfkDepth& dd = depth_[static_cast<size_t>(d - 2)];
      filter_kernel(dd.grid, dd.filterable, [&](uint32_t s) { return dd.vertex[s].hit.p; }, x.p, UINT32_MAX,
                    prm_.kernel, &members);
      const int m = static_cast<int>(members.size());
      const double n = 1.0 / static_cast<double>(m + 1);  // expected count of each technique at x_d
      const Vec3 wo = -ray.d;
      const SurfaceScatter sx(x, *surf.bsdf);
      const BounceUniforms u(rng);
      const double u_choice = rng.next();
      // column[t] = n p_t(w) for the m members and the own technique (entry m).
      const auto fill = [&](std::vector<double>* col, const Vec3& w) {
        col->assign(static_cast<size_t>(m + 1), 0.0);
        for (int j = 0; j < m; ++j) {
          const PfkPassVertex& v = dd.vertex[members[j]];
          (*col)[j] = n * SurfaceScatter(v.hit, *world_.surface(v.hit.shape_id).bsdf).pdf(v.wo, w, TransportMode::kRadiance);
        }
        (*col)[m] = n * sx.pdf(wo, w, TransportMode::kRadiance);
      };
      path.emplace_back();
      path.back().x = x;
      path.back().wo = wo;
      path.back().self = m;
      // Next-event estimation at x_d: the light sample, a classical technique at this vertex.
      if (const auto choice = lights_.sample(u[BounceDim::kLightSelect])) {
        const auto ls = choice->light->sample_li_point(x.p, {u[BounceDim::kLightU], u[BounceDim::kLightV]});
        if (ls && ls->pdf > 0 && !is_black(ls->li)) {
          const Rgb fl = sx.f(wo, ls->wi, TransportMode::kRadiance) * sx.abs_cos_shading(ls->wi);
          const bool blocked = is_black(fl) || (std::isinf(ls->distance) ? scene.occluded(spawn_ray(x, ls->wi))
                                                                          : scene.occluded(spawn_ray_to(x, ls->p_light)));
          ++rc.shadow;
          if (!blocked) {
            const double pl = choice->pmf * ls->pdf;
            PfkLevelState& l = path.back();
            l.w = ls->wi;
            if (choice->light->is_delta()) {
              l.column.assign(1, pl);  // only the light sample can find a delta light
              l.own = 0;
            } else {
              fill(&l.column, ls->wi);
              l.column.push_back(pl);
              l.own = m + 1;
            }
            const FilteringWeight w = weigh(true, choice->light->is_delta());
            out += beta * fl * ls->li * inverse_or_zero(w.denominator);
          }
        }
      }
      // The direction at x_d: one technique chosen uniformly among the m + 1.
      const int t = std::min(static_cast<int>(u_choice * static_cast<double>(m + 1)), m);
      Vec3 wd;
      if (t < m) {
        const PfkPassVertex& v = dd.vertex[members[t]];
        if (!v.has_dir) return out;  // the technique sampled no direction: this output path ends
        wd = v.wi;
      } else {
        const auto bs = sx.sample(wo, u[BounceDim::kBsdfLobe], {u[BounceDim::kBsdfU], u[BounceDim::kBsdfV]},
                                  TransportMode::kRadiance);
        if (!bs || bs->is_delta() || !(bs->pdf > 0)) return out;
        wd = bs->wi;
      }
      const Rgb fd = sx.f(wo, wd, TransportMode::kRadiance) * sx.abs_cos_shading(wd);
      if (is_black(fd)) return out;
      PfkLevelState& l = path.back();
      l.w = wd;
      fill(&l.column, wd);
      l.own = t;
      if (!(l.column[static_cast<size_t>(t)] > 0)) return out;
      spawn_ray_into(x, wd, &ray);
      SurfacePoint next;
      ++rc.extension;
      const bool found = scene.intersect_point(ray, &next);
      // Emission at x_{d+1}: the light sample at x_d could have found it too (its entry appended).
      for_each_filtered_emission(world_, lights_, x, wd, found ? &next : nullptr, [&](const Rgb& le, double pl) {
        path.back().column.push_back(pl);
        const FilteringWeight w = weigh(true, false);
        path.back().column.pop_back();
        out += beta * fd * le * inverse_or_zero(w.denominator);
      });
      beta *= fd;
      scattered_at = d;
      if (!found) return out;
      x = next;
    }
    // Light scattered beyond the last filtered vertex: the path tracer, its emission at the first hit
    // left out (weighted above).
    const Rgb L = suffix_[static_cast<size_t>(scattered_at)]->li(ray, rng, rc, nullptr, true);
    if (is_black(L) && !record) return out;
    const FilteringWeight w = weigh(false, false);
    return out + beta * L * inverse_or_zero(w.denominator);
  }

 private:
  const World& world_;
  const RenderSettings& st_;
  PfkParams prm_;
  const LightSampler& lights_;
  PfkRecorder* recorder_;
  const Pf1Pass* pass1_ = nullptr;  // the pass being filtered (set by begin_pass)
  int depths_ = 1;
  std::deque<RenderSettings> suffix_settings_;
  std::vector<std::unique_ptr<PathTracer<ExactTerms>>> suffix_;
  std::vector<PfkDepth> depth_;
};

template <class Weights>
int64_t render_pfk_with(const World& world, const RenderSettings& st, Film& film) {
  const PfkParams prm = pfk_params(world, st);
  const LightSampler lights(world);
  PfkContinuation<Weights> cont(world, st, prm, lights);
  return render_path_filter_with<Weights>(world, st, film, prm.kernel, lights, cont);
}

}  // namespace tb::detail

// pfk's MMIS weights on the output paths the renderer forms (lib/integrator/path_filter_multi.h; West et
// al. 2022, Eq. 13 and Eq. 14): on the Cornell box and glossy.json (24 x 24, 16 prefixes per pixel, K = 3
// filtered vertices, radius 0.02 x the scene's bounding-sphere radius, at most 6 members per kernel so that
// the techniques can be enumerated; fixed seed from the check seed), for every recorded output path of up
// to 200 queries, the techniques that can produce it are enumerated independently of the renderer: at
// each filtered vertex x_d, a brute-force search over the pass's depth-d prefix vertices within r (the
// nearest max_members, the query kept at d = 1), each with its expected count (1 at d = 1, 1 / M_d at
// d >= 2, M_d = members + the vertex's own technique) times its density of the path's direction, the own
// technique at d >= 2, and the light sample where the path ends on an emitter. The sum of their weights,
// (sum over every combination of the product of its counted densities: filtering_sum_of_products, the
// exponential form of Eq. 14) / (the renderer's denominator), must be one to 1e-12. Deterministic.
// Negative control: the weighting whose product of sums leaves out x_d's own technique for d >= 2
// (validate/render/broken_path_filter.h) must depart from one on every path whose own technique has a
// share above 1e-9 of S_d at some x_d, d >= 2 (smaller shares vanish in the rounding of the sum).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "estimators/mmis_filtering.h"
#include "lib/core/hash.h"
#include "lib/integrator/path_filter_multi.h"
#include "lib/path/scattering.h"
#include "validate/registry.h"
#include "validate/render/broken_path_filter.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

constexpr double kTol = 1e-12;

// The counted densities n_t p_t(w) of every technique at level d (0-based) of path p, found by brute force.
std::vector<double> independent_column(const World& world, const PfkSample& s, const PfkSampledPath& p, size_t d) {
  const PfkPathLevel& lv = p.levels[d];
  const bool last = d + 1 == p.levels.size();
  if (last && p.delta_light) return {lv.column.back()};  // only the light sample finds a delta light
  struct Near {
    double d2;
    uint32_t slot;
    const PfkPassVertex* v;
  };
  std::vector<Near> found;
  const double r2 = s.params.kernel.radius * s.params.kernel.radius;
  for (const PfkPassVertex& v : s.depth_vertices[d]) {
    const Vec3 diff = v.hit.p - lv.x.p;
    const double d2 = glm::dot(diff, diff);
    const bool self = d == 0 && v.slot == p.query_slot;
    if (self || d2 <= r2) found.push_back({self ? -1.0 : d2, v.slot, &v});
  }
  std::sort(found.begin(), found.end(),
            [](const Near& a, const Near& b) { return a.d2 < b.d2 || (a.d2 == b.d2 && a.slot < b.slot); });
  if (static_cast<int>(found.size()) > s.params.kernel.max_members)
    found.resize(static_cast<size_t>(s.params.kernel.max_members));
  const double n = d == 0 ? 1.0 : 1.0 / static_cast<double>(found.size() + 1);
  std::vector<double> col;
  for (const Near& f : found)
    col.push_back(n * SurfaceScatter(f.v->hit, *world.surface(f.v->hit.shape_id).bsdf)
                          .pdf(f.v->wo, lv.w, TransportMode::kRadiance));
  if (d > 0)
    col.push_back(n * SurfaceScatter(lv.x, *world.surface(lv.x.shape_id).bsdf).pdf(lv.wo, lv.w, TransportMode::kRadiance));
  if (last && p.light_entry) col.push_back(lv.column.back());  // the light sample's density (n = 1)
  return col;
}

struct SceneTally {
  int64_t paths = 0, deep = 0, own_positive = 0;
  double max_dev = 0.0, min_dev_broken = INFINITY, max_dev_broken = 0.0, members2 = 0.0;
  int64_t levels2 = 0;
};

SceneTally tally_scene(const CheckContext& ctx, const std::string& file, bool broken) {
  SceneTally t;
  const auto world = load_scene_at_resolution(file, 24, 24);
  RenderSettings st;
  st.spp = 16;
  st.passes = 1;
  st.max_depth = 5;
  st.seed = hash_values(ctx.seed, hash_string("integrator.pfk.weights_sum_to_one"), hash_string(file));
  st.params["radius"] = 0.02 * world->bounds().radius;
  st.params["max_members"] = 6;
  st.params["vertices"] = 3;
  const PfkSample s = pfk_sample_paths(*world, st, 200);
  std::vector<std::vector<double>> cols;
  std::vector<PfkLevel> view;
  for (const PfkSampledPath& p : s.paths) {
    cols.clear();
    view.clear();
    bool own_positive = false;
    for (size_t d = 0; d < p.levels.size(); ++d) {
      cols.push_back(independent_column(*world, s, p, d));
      const PfkPathLevel& lv = p.levels[d];
      view.push_back({lv.column, lv.own, lv.self});
      // The own technique carries a representable share of S_d (> 1e-9): leaving it out must show.
      if (d > 0 && lv.self >= 0 && static_cast<size_t>(lv.self) < lv.column.size() &&
          !(d + 1 == p.levels.size() && p.delta_light)) {
        double sum = 0.0;
        for (double v : lv.column) sum += v;
        if (lv.column[static_cast<size_t>(lv.self)] > 1e-9 * sum) own_positive = true;
      }
      if (d == 1) {
        ++t.levels2;
        t.members2 += static_cast<double>(lv.self);  // the own technique follows the m members
      }
    }
    std::vector<int> sizes;
    for (const auto& c : cols) sizes.push_back(static_cast<int>(c.size()));
    // Every technique's counted density summed: the sum of products over all combinations (Eq. 14 expanded).
    const double numerators = filtering_sum_of_products(std::span<const int>(sizes), [&](size_t d, int j) {
      return cols[d][static_cast<size_t>(j)];
    });
    const double den = broken ? pfk_weight_omitting_own(view).denominator : p.weight.denominator;
    const double dev = den > 0 ? std::abs(numerators / den - 1.0) : INFINITY;
    ++t.paths;
    t.deep += p.levels.size() >= 3;
    t.max_dev = std::max(t.max_dev, std::isfinite(dev) ? dev : INFINITY);
    if (own_positive) {
      ++t.own_positive;
      t.min_dev_broken = std::min(t.min_dev_broken, dev);
      t.max_dev_broken = std::max(t.max_dev_broken, dev);
    }
  }
  return t;
}

CheckResult run_pfk_weights(const CheckContext& ctx, bool broken) {
  CheckResult r;
  r.statistic_name = broken ? "min |sum of weights - 1|" : "max |sum of weights - 1|";
  bool ok = true;
  double stat = broken ? INFINITY : 0.0;
  int64_t total = 0;
  std::string msg;
  for (const std::string file : {"cornell-box.json", "glossy.json"}) {
    const SceneTally t = tally_scene(ctx, file, broken);
    total += t.paths;
    const double mean2 = t.levels2 > 0 ? t.members2 / double(t.levels2) : 0.0;
    r.details[file] = {{"output_paths", t.paths},
                       {"paths_filtered_at_3_vertices", t.deep},
                       {"mean_members_at_x2", mean2},
                       {"max_dev", t.max_dev},
                       {"paths_with_own_share_above_1e-9", t.own_positive}};
    if (!broken) {
      ok = ok && t.paths > 0 && t.deep >= t.paths / 4 && mean2 >= 1.0 && t.max_dev <= kTol;
      stat = std::max(stat, t.max_dev);
      msg += fmt::format("{}: {} output paths ({} filtered at 3 vertices, mean {:.2f} members at x_2), max |sum - 1| "
                         "= {:.3g}; ",
                         file, t.paths, t.deep, mean2, t.max_dev);
    } else {
      ok = ok && t.own_positive > 0 && t.min_dev_broken > kTol;
      stat = std::min(stat, t.min_dev_broken);
      msg += fmt::format("{}: omitting the own technique, min |sum - 1| over the {} paths with an own share > 1e-9 "
                         "= {:.3g} (max {:.3g}); ",
                         file, t.own_positive, t.min_dev_broken, t.max_dev_broken);
    }
  }
  r.samples = total;
  r.statistic = stat;
  r.passed = ok;
  r.message = msg + fmt::format("tolerance {:.0e}", kTol);
  return r;
}

TB_REGISTER_CHECK({.name = "integrator.pfk.weights_sum_to_one",
                   .description = "pfk's MMIS weights (K = 3) over every technique that can produce a sampled output "
                                  "path, enumerated independently, sum to one (1e-12), Cornell box and glossy.json",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_pfk_weights(c, false); }});
TB_REGISTER_CHECK({.name = "integrator.pfk.weights_sum_to_one.negative_control",
                   .description = "pfk weights whose product of sums omits the own technique of x_2 and x_3 must not "
                                  "sum to one on any output path where that technique has a share above 1e-9",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_pfk_weights(c, true); }});

}  // namespace
}  // namespace tb

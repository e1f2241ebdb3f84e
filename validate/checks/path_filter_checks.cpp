// pf1's MMIS weights on the kernels the renderer forms (lib/integrator/path_filter.h; West et al. 2022,
// Eq. 13 and Eq. 14 with one filtered vertex): on the Cornell box (24 x 24, 16 prefixes per pixel,
// radius 0.02 x the scene's bounding-sphere radius so that kernels hold several prefixes, fixed seed
// from the check seed), for every sampled output path of up to 400 kernels the weights of all the
// techniques that can produce it (every member's conditional technique, and a classical term standing
// in for the query's light sample) sum to one to 1e-12. Deterministic, never rerun.
// Negative control: the weighting that omits the query's own prefix from the denominator
// (validate/render/broken_path_filter.h) must depart from one wherever the query's density is positive.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/integrator/path_filter.h"
#include "validate/registry.h"
#include "validate/render/broken_path_filter.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

constexpr double kTol = 1e-12;

CheckResult run_pf1_weights(const CheckContext& ctx, bool broken) {
  CheckResult r;
  r.statistic_name = "max |sum of weights - 1|";
  const auto world = load_scene_at_resolution("cornell-box.json", 24, 24);
  RenderSettings st;
  st.spp = 16;
  st.passes = 1;
  st.max_depth = 5;
  st.seed = hash_values(ctx.seed, hash_string("integrator.pf1.weights_sum_to_one"));
  st.params["radius"] = 0.02 * world->bounds().radius;
  const std::vector<Pf1Kernel> kernels = pf1_sample_kernels(*world, st, 400);
  double max_dev = 0.0, min_dev_broken = INFINITY;
  int64_t paths = 0, multi = 0, members = 0, positive_query = 0;
  std::vector<double> column;
  for (const Pf1Kernel& k : kernels) {
    const int m = k.members;
    members += m;
    column.resize(static_cast<size_t>(m));
    for (int s = 0; s < m; ++s) {
      if (!k.sampled[static_cast<size_t>(s)] || !(k.pdf[static_cast<size_t>(s * m + s)] > 0)) continue;
      for (int j = 0; j < m; ++j) column[static_cast<size_t>(j)] = k.pdf[static_cast<size_t>(j * m + s)];
      const double p_query = column[static_cast<size_t>(k.query)];
      for (const double classical : {0.0, p_query}) {
        double sum = 0.0, den = 0.0;
        for (int own = 0; own < m; ++own) {
          const FilteringWeight w = broken ? pf1_weight_omitting_query(column, own, k.query, classical)
                                           : pf1_mmis_weight(column, own, classical);
          sum += w.weight;
          den = w.denominator;
        }
        if (classical > 0) sum += classical / den;  // the classical technique's own weight
        const double dev = std::abs(sum - 1.0);
        if (!std::isfinite(dev)) {
          max_dev = INFINITY;
        } else {
          max_dev = std::max(max_dev, dev);
        }
        ++paths;
        multi += m > 1;
        if (p_query > 0) {
          ++positive_query;
          min_dev_broken = std::min(min_dev_broken, std::isfinite(dev) ? dev : INFINITY);
        }
      }
    }
  }
  r.samples = paths;
  r.details["kernels"] = kernels.size();
  r.details["output_paths"] = paths;
  r.details["paths_in_kernels_with_2_or_more_members"] = multi;
  r.details["mean_members"] = kernels.empty() ? 0.0 : double(members) / double(kernels.size());
  r.details["paths_with_positive_query_density"] = positive_query;
  if (!broken) {
    r.statistic = max_dev;
    r.passed = paths > 0 && multi >= paths / 4 && max_dev <= kTol;
    r.message = fmt::format("{} output paths of {} kernels (mean {:.2f} members, {} paths in kernels of >= 2): max "
                            "|sum - 1| = {:.3g} (tolerance {:.0e})",
                            paths, kernels.size(), kernels.empty() ? 0.0 : double(members) / double(kernels.size()),
                            multi, max_dev, kTol);
  } else {
    r.statistic = min_dev_broken;
    r.passed = positive_query > 0 && min_dev_broken > kTol;
    r.message = fmt::format("omitting the query's prefix: min |sum - 1| over the {} output paths with positive query "
                            "density = {:.3g} (caught when > {:.0e}); max {:.3g}",
                            positive_query, min_dev_broken, kTol, max_dev);
  }
  return r;
}

TB_REGISTER_CHECK({.name = "integrator.pf1.weights_sum_to_one",
                   .description = "pf1's MMIS weights over every technique that can produce a sampled output path "
                                  "(each kernel member, the classical term) sum to one (1e-12), Cornell box kernels",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_pf1_weights(c, false); }});
TB_REGISTER_CHECK({.name = "integrator.pf1.weights_sum_to_one.negative_control",
                   .description = "pf1 weights whose denominator omits the query's own prefix must not sum to one on "
                                  "any output path with positive query density",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext& c) { return run_pf1_weights(c, true); }});

}  // namespace
}  // namespace tb

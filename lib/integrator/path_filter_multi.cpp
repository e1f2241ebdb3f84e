#include "lib/integrator/path_filter_multi.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lib/integrator/path_filter_multi_impl.h"

namespace tb {

FilteringWeight pfk_mmis_weight(std::span<const PfkLevel> levels) {
  if (levels.size() > static_cast<size_t>(kPfkMaxVertices) + 1)
    throw std::invalid_argument("pfk_mmis_weight: too many filtered vertices");
  int sizes[kPfkMaxVertices + 1] = {}, owns[kPfkMaxVertices + 1] = {};
  for (size_t d = 0; d < levels.size(); ++d) {
    sizes[d] = static_cast<int>(levels[d].column.size());
    owns[d] = levels[d].own;
  }
  // West et al. 2022, Eq. 14 as a product of sums: one kernel per filtered vertex.
  return filtering_mmis_weight(std::span<const int>(sizes, levels.size()), std::span<const int>(owns, levels.size()),
                               [&](size_t d, int t) { return levels[d].column[static_cast<size_t>(t)]; });
}

PfkParams pfk_params(const World& world, const RenderSettings& st) {
  PfkParams p;
  p.kernel = pf1_params(world, st);
  if (auto it = st.params.find("vertices"); it != st.params.end()) p.vertices = static_cast<int>(std::llround(it->second));
  if (p.vertices < 1 || p.vertices > kPfkMaxVertices)
    throw std::invalid_argument("pfk: vertices must be in [1, " + std::to_string(kPfkMaxVertices) + "]");
  return p;
}

std::vector<std::pair<std::string, std::string>> pfk_parameter_list() {
  auto list = pf1_parameter_list();
  list.insert(list.begin(), {"vertices", "number K of consecutive camera vertices filtered, x_1 .. x_K (default 2; "
                                         "1 is pf1; capped at max_depth)"});
  return list;
}

PfkSample pfk_sample_paths(const World& world, const RenderSettings& st, size_t max_queries) {
  PfkSample out;
  out.params = pfk_params(world, st);
  const LightSampler lights(world);
  // The first pass, as render_path_filter_with traces it.
  RenderSettings one = st;
  one.spp = std::max<int64_t>(1, st.spp / std::max<int64_t>(1, st.passes));
  one.passes = 1;
  detail::PfkRecorder rec;
  {
    const detail::PathTracer<ExactTerms> pt(world, one, lights);
    detail::Pf1Pass pass;
    detail::pf1_trace_prefixes(world, one, pt, lights, 0, one.spp, out.params.kernel.radius, &pass);
    rec.record_slots.assign(pass.prefixes.size(), 0);
    const size_t stride = std::max<size_t>(1, pass.filterable.size() / std::max<size_t>(1, max_queries));
    for (size_t k = 0, n = 0; k < pass.filterable.size() && n < max_queries; k += stride, ++n)
      rec.record_slots[pass.filterable[k]] = 1;
  }
  detail::PfkContinuation<PfkExactWeights> cont(world, one, out.params, lights, &rec);
  Film film(world.camera().width(), world.camera().height());
  detail::render_path_filter_with<PfkExactWeights>(world, one, film, out.params.kernel, lights, cont);
  // The recorded pass's prefix vertices (the continuation keeps the last pass's).
  out.depth_vertices.push_back(rec.depth1);
  for (const detail::PfkDepth& dd : cont.depth_data()) {
    auto& v = out.depth_vertices.emplace_back();
    for (uint32_t s : dd.filterable) v.push_back(dd.vertex[s]);
  }
  // Paths of one query come from one thread in order: a stable sort by query gives a fixed order.
  std::stable_sort(rec.paths.begin(), rec.paths.end(),
                   [](const PfkSampledPath& a, const PfkSampledPath& b) { return a.query_slot < b.query_slot; });
  out.paths = std::move(rec.paths);
  return out;
}

int64_t render_pfk(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_pfk_with<PfkExactWeights>(world, st, film);
}

}  // namespace tb

#include "lib/integrator/path_filter.h"

#include <cmath>
#include <mutex>
#include <stdexcept>

#include "lib/integrator/path_filter_impl.h"

namespace tb {

FilteringWeight pf1_mmis_weight(std::span<const double> column, int own, double classical) {
  const int prefixes[1] = {static_cast<int>(column.size())};
  const int owns[1] = {own};
  return filtering_mmis_weight(std::span<const int>(prefixes), std::span<const int>(owns),
                               [&](size_t, int j) { return column[static_cast<size_t>(j)]; }, classical);
}

Pf1Params pf1_params(const World& world, const RenderSettings& st) {
  Pf1Params p;
  p.radius = 0.01 * world.bounds().radius;
  if (auto it = st.params.find("radius"); it != st.params.end()) p.radius = it->second;
  if (auto it = st.params.find("max_members"); it != st.params.end())
    p.max_members = static_cast<int>(std::llround(it->second));
  if (!(p.radius > 0) || !std::isfinite(p.radius)) throw std::invalid_argument("pf1: radius must be > 0");
  if (p.max_members < 1 || p.max_members > 4096) throw std::invalid_argument("pf1: max_members must be in [1, 4096]");
  return p;
}

std::vector<std::pair<std::string, std::string>> pf1_parameter_list() {
  return {{"radius", "kernel radius around the first camera vertex (default 0.01 x the scene's bounding-sphere radius)"},
          {"max_members", "largest kernel, the query's own prefix and its nearest neighbours (default 32)"}};
}

namespace {
std::mutex g_timing_mutex;
Pf1Timing g_timing;
}  // namespace

void detail::pf1_store_timing(const Pf1Stats& s) {
  std::lock_guard<std::mutex> lock(g_timing_mutex);
  g_timing.prefix_seconds = s.prefix_seconds;
  g_timing.filter_seconds = s.filter_seconds;
  g_timing.passes = s.passes;
  g_timing.mean_members = s.queries > 0 ? static_cast<double>(s.members) / static_cast<double>(s.queries) : 0.0;
}

Pf1Timing pf1_last_timing() {
  std::lock_guard<std::mutex> lock(g_timing_mutex);
  return g_timing;
}

std::vector<Pf1Kernel> pf1_sample_kernels(const World& world, const RenderSettings& st, size_t max_kernels) {
  const Pf1Params prm = pf1_params(world, st);
  const LightSampler lights(world);
  const detail::PathTracer<ExactTerms> pt(world, st, lights);
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  detail::Pf1Pass pass;
  detail::pf1_trace_prefixes(world, st, pt, lights, 0, spp_pass, prm.radius, &pass);
  std::vector<Pf1Kernel> out;
  if (pass.filterable.empty() || max_kernels == 0) return out;
  const size_t stride = std::max<size_t>(1, pass.filterable.size() / max_kernels);
  std::vector<uint32_t> members;
  for (size_t k = 0; k < pass.filterable.size() && out.size() < max_kernels; k += stride) {
    Pf1Kernel kern;
    kern.query = detail::pf1_kernel(pass, pass.filterable[k], prm, &members);
    kern.members = static_cast<int>(members.size());
    detail::pf1_kernel_pdfs(world, pass, members, &kern.pdf);
    for (uint32_t s : members) kern.sampled.push_back(pass.prefixes[s].has_dir);
    out.push_back(std::move(kern));
  }
  return out;
}

int64_t render_pf1(const World& world, const RenderSettings& st, Film& film) {
  return detail::render_pf1_with<Pf1ExactWeights>(world, st, film);
}

}  // namespace tb

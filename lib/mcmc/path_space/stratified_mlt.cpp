#include "lib/mcmc/path_space/stratified_mlt.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/differential/variance_bound.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/mcmc/stratified_target.h"

namespace tb::path_space {

namespace {
constexpr uint64_t kPilotKey = hash_string("mlt.stratified.pilot");
}  // namespace

double StratifiedPathTarget::ratio(const MltPath& x, const PathDensities& d) const {
  // The camera-ordered vertex list of Eq. 21: camera[j] = x_{k-j}, pdf_fwd = its camera-walk area
  // density pE[k-j] (the density of sampling it from x_{k-j+1}, x_{k-j+2}).
  const size_t n = x.v.size();
  std::vector<PathVertex> camera(x.v.rbegin(), x.v.rend());
  for (size_t j = 0; j < n; ++j) camera[j].pdf_fwd = d.pE[n - 1 - j];
  return differential::subpath_variance_ratio(*ctx_->world, camera, static_cast<int>(n), /*s=*/0, mis_reduction_);
}

double StratifiedPathTarget::ratio(const MltPath& x) const {
  if (x.v.size() < 2) return 1.0;
  return ratio(x, path_densities(*ctx_, x.v, DiracPolicy::kCoefficient));
}

double StratifiedPathTarget::technique_sum(const MltPath& x) const {
  if (x.v.size() < 2) return 0.0;
  const PathDensities d = path_densities(*ctx_, x.v, DiracPolicy::kCoefficient);
  double p = 0.0;
  for (int s = 0; s < x.segments() + 1; ++s) p += technique_density(d, s);  // t = k + 1 - s >= 1
  return p;
}

double StratifiedPathTarget::operator()(const MltPath& x, const Rgb& f) const {
  const double y = luminance(f);
  if (!(y > 0.0) || x.v.size() < 2) return 0.0;
  const PathDensities d = path_densities(*ctx_, x.v, DiracPolicy::kCoefficient);
  double p = 0.0;
  for (int s = 0; s < x.segments() + 1; ++s) p += technique_density(d, s);
  // No MC estimate to bound (no technique samples x): the plain target, scaled.
  if (!(p > 0.0) || !std::isfinite(p)) return y / B_;
  const double r = ratio(x, d);
  return mcmc::stratified_target(y, p, r, B_);  // Eq. 8 footnote: min{ p r~, Y(f) / B }
}

double stratified_pilot_brightness(const PathContext& ctx, uint64_t seed, int64_t n, int max_depth) {
  return bdpt_brightness(ctx, seed, kPilotKey, n, max_depth);
}

MltTarget stratified_mlt_target(const PathContext& ctx, const RenderSettings& st, const StratifiedMltSettings& ss) {
  MltTarget t;
  double B = ss.brightness;
  if (!(B > 0.0)) {
    const int64_t P = ctx.world->camera().pixel_count();
    t.pilot_samples = ss.pilot > 0 ? ss.pilot : std::max<int64_t>(1024, P);
    B = stratified_pilot_brightness(ctx, st.seed, t.pilot_samples, std::max(0, st.max_depth));
  }
  t.brightness = B;
  if (!(B > 0.0) || !std::isfinite(B)) return t;  // nothing found: the plain target (density empty)
  const StratifiedPathTarget w(ctx, B, ss.mis_reduction);
  t.density = [w](const MltPath& x, const Rgb& f) { return w(x, f); };
  return t;
}

MltStats run_mlt_stratified(const World& world, const RenderSettings& settings, Film& film,
                            const StratifiedMltSettings& ss, MltOptions options) {
  options.target = [ss](const PathContext& ctx, const RenderSettings& st) { return stratified_mlt_target(ctx, st, ss); };
  return run_mlt(world, settings, film, options);
}

}  // namespace tb::path_space

namespace tb {

int64_t render_mlt_stratified(const World& world, const RenderSettings& settings, Film& film) {
  path_space::StratifiedMltSettings ss;
  for (const auto& [name, value] : settings.params) {
    if (name == "mis_reduction") {
      if (value != 0 && value != 1)
        throw std::invalid_argument(fmt::format("parameter mis_reduction = {} must be 0 or 1", value));
      ss.mis_reduction = value == 1;
    } else if (name == "pilot") {
      if (!(value >= 0) || value != std::floor(value))
        throw std::invalid_argument(fmt::format("parameter pilot = {} must be a non-negative integer", value));
      ss.pilot = static_cast<int64_t>(value);
    } else {
      throw std::invalid_argument(fmt::format("mlt-stratified: unknown parameter '{}'", name));
    }
  }
  const path_space::MltStats stats = path_space::run_mlt_stratified(world, settings, film, ss);
  path_space::fill_report(stats, settings.report);
  return stats.chains;
}

}  // namespace tb

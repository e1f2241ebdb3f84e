#include "lib/mcmc/path_space/manifold_perturbation.h"

#include <cmath>
#include <stdexcept>

#include "lib/camera/camera.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/path/dirac.h"
#include "lib/scene/world.h"

namespace tb::path_space {

namespace {
constexpr auto kRelaxed = std::memory_order_relaxed;
}  // namespace

ManifoldPerturbation::ManifoldPerturbation(const PathContext& ctx, std::shared_ptr<HsltCounters> counters, double r1,
                                           double r2)
    : ctx_(&ctx), counters_(counters ? std::move(counters) : std::make_shared<HsltCounters>()), lens_(ctx, r1, r2),
      hslt_(ctx, HsltMutation::kDefaultGamma, nullptr, false, HsltMutation::kImageFraction, false) {}

int ManifoldPerturbation::chain_start(const MltPath& x) const {
  int c = chain_end(x) - 1;
  while (c >= 0 && is_dirac_surface(x.v[static_cast<size_t>(c)])) --c;
  return c;
}

bool ManifoldPerturbation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 3 || x.v[static_cast<size_t>(k)].kind != VertexKind::kCamera || !ctx_->world->camera().lens_is_delta())
    return false;
  const int j = chain_end(x);
  if (j < 2) return false;
  const PathVertex& b = x.v[static_cast<size_t>(j)];
  if (!b.is_surface() || b.bsdf == nullptr || b.delta) return false;
  if (!is_dirac_surface(x.v[static_cast<size_t>(j - 1)])) return false;  // the lens perturbation's case
  const int c = chain_start(x);
  if (c < 0) return false;
  const PathVertex& a = x.v[static_cast<size_t>(c)];
  if (a.infinite) return false;
  if (c == 0) return a.light != nullptr;
  return a.is_surface() && a.bsdf != nullptr;
}

bool manifold_applies(const ManifoldPerturbation& m, const MltPath& x) { return m.applicable(x); }

MltPath ManifoldPerturbation::subpath(const MltPath& x, const PathVertex* end) const {
  const int c = chain_start(x), j = chain_end(x);
  MltPath s;
  s.v.assign(x.v.begin() + c, x.v.begin() + j + 1);
  if (end) s.v.back() = *end;
  return s;
}

ManifoldPerturbation::WalkOutcome ManifoldPerturbation::solve_chain(const MltPath& from, const MltPath& to) const {
  WalkOutcome out;
  const int c = chain_start(from), j = chain_end(from);
  const MltPath start = subpath(from, &to.v[static_cast<size_t>(j)]);
  const std::optional<HsltPath> S = hslt_.hslt_path(start);
  if (!S) return out;
  // Kaplanyan 2014, Sec. 4.4: a specular vertex has h^perp = 0.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(2 * S->interior_count());
  out.walk = hslt_.walk(*S, zero);
  if (out.walk.status != HsltWalkStatus::kConverged) return out;
  const MltPath chain = hslt_.path_at(start, out.walk.path);
  MltPath y = to;
  for (int i = c + 1; i < j; ++i) y.v[static_cast<size_t>(i)] = chain.v[static_cast<size_t>(i - c)];
  out.path = std::move(y);
  return out;
}

bool ManifoldPerturbation::lands(const MltPath& from, const MltPath& to) const {
  const WalkOutcome w = solve_chain(from, to);
  if (!w.path) return false;
  const std::optional<HsltPath> T = hslt_.hslt_path(subpath(to));
  return T && hslt_max_vertex_distance(w.walk.path, *T) < kLandingTolerance;
}

double ManifoldPerturbation::geometry_term(const MltPath& x) const {
  const std::optional<HsltPath> S = hslt_.hslt_path(subpath(x));
  if (!S) return 0.0;
  return hslt_.measure_factor(*S, std::vector<bool>(static_cast<size_t>(S->interior_count()), true));
}

ManifoldPerturbation::DensityParts ManifoldPerturbation::density_parts(const MltPath& x, const MltPath& y) const {
  DensityParts p;
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return p;
  const int j = chain_end(x), c = chain_start(x);
  if (chain_end(y) != j || chain_start(y) != c) return p;
  for (int i = 0; i <= k; ++i)
    if ((i <= c || i == k) && !same_vertex(x.v[static_cast<size_t>(i)], y.v[static_cast<size_t>(i)])) return p;
  for (int i = c + 1; i < k; ++i)
    if (i != j && transmits_from_camera_side(x, i) != transmits_from_camera_side(y, i)) return p;
  for (int i = c + 1; i < j; ++i) {
    const Hit& a = x.v[static_cast<size_t>(i)].hit;
    const Hit& b = y.v[static_cast<size_t>(i)].hit;
    if (a.shape_id != b.shape_id || a.prim_id != b.prim_id) return p;  // the walk stays on its surfaces
  }
  const auto rx = path_raster(*ctx_, x), ry = path_raster(*ctx_, y);
  if (!rx || !ry) return p;
  p.structure = true;
  p.lens = lens_.kernel_density(*ry - *rx) * lens_.raster_jacobian(y);
  p.geometry = geometry_term(y);
  if (!(p.lens > 0.0) || !(p.geometry > 0.0)) return p;
  p.forward_lands = lands(x, y);
  if (!p.forward_lands) return p;
  p.reverse_lands = lands(y, x);
  return p;
}

double ManifoldPerturbation::density(const MltPath& x, const MltPath& y) const {
  const DensityParts p = density_parts(x, y);
  if (!p.structure || !p.forward_lands || !p.reverse_lands) return 0.0;
  const double t = p.lens * p.geometry;
  return std::isfinite(t) ? t : 0.0;
}

std::optional<MltPath> ManifoldPerturbation::propose(const MltPath& x, Uniforms& u) const {
  HsltCounters& cn = *counters_;
  if (!applicable(x)) {
    cn.not_applicable.fetch_add(1, kRelaxed);
    return std::nullopt;
  }
  cn.proposals.fetch_add(1, kRelaxed);
  const Vec2 uo = u.next2();
  // 1. the lens part: y_j .. y_{k-1} traced from the perturbed raster position.
  const std::optional<MltPath> traced = lens_.trace(x, lens_.sample_offset(uo));
  if (!traced) return std::nullopt;
  // 2. the manifold part: the specular chain between x_c and y_j by the walk.
  const WalkOutcome w = solve_chain(x, *traced);
  cn.forward_status[static_cast<size_t>(w.walk.status)].fetch_add(1, kRelaxed);
  cn.iterations_all.fetch_add(w.walk.iterations, kRelaxed);
  if (!w.path) return std::nullopt;
  cn.iterations_converged.fetch_add(w.walk.iterations, kRelaxed);
  const MltPath& y = *w.path;
  // 3. the reverse walk (Jakob and Marschner 2012, Sec. 5; Kaplanyan 2014, Sec. 5.2).
  if (!applicable(y) || chain_end(y) != chain_end(x) || chain_start(y) != chain_start(x) || !lands(y, x)) {
    cn.non_reversible.fetch_add(1, kRelaxed);
    return std::nullopt;
  }
  cn.generated.fetch_add(1, kRelaxed);
  return y;
}

PathMutationList make_memlt_mixture(const PathContext& ctx, const PathMutationSettings& s,
                                    const std::shared_ptr<HsltCounters>& counters, double r2) {
  const PathMutationInfo* bidir = find_path_mutation("bidirectional");
  const PathMutationInfo* manifold = find_path_mutation("manifold");
  PathMutationList out;
  out.push_back(bidir->make(ctx, s, bidir->weight));
  out.push_back(std::make_shared<const PathProposalMutation<ManifoldPerturbation>>(
      "manifold", manifold->weight, ManifoldPerturbation(ctx, counters, 0.1, r2), manifold_applies));
  return out;
}

}  // namespace tb::path_space

namespace tb {

int64_t render_memlt(const World& world, const RenderSettings& settings, Film& film) {
  using namespace path_space;
  const auto counters = std::make_shared<HsltCounters>();
  const auto it = settings.params.find("r2");
  const double r2 = it == settings.params.end() ? 0.0 : it->second;
  MltOptions o;
  o.mutations = [counters, r2](const PathContext& ctx, const PathMutationSettings& s) {
    return make_memlt_mixture(ctx, s, counters, r2);
  };
  const MltStats stats = run_mlt(world, settings, film, o);
  fill_report(stats, settings.report);
  print_walk_statistics("memlt (Table 3)", "manifold", "manifold", *counters, stats);
  return stats.chains;
}

}  // namespace tb

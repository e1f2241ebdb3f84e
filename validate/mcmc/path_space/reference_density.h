// Reference proposal densities of the path-space mutations, assembled independently of the
// mutations' own density() code: the added vertices' densities are read from path_densities(y)
// (lib/path/path.h, the per-vertex pL / pE arrays every MIS weight uses), not from the step-by-step
// pdf_next calls of the mutation. The discrete choices (deletion, addition, split probabilities)
// are the mutation's.
//
// WithReferenceDensity turns a Metropolis-Hastings kernel (estimators/mcmc/metropolis_hastings.h)
// into the MoveKernel the pairwise detailed-balance checker (validate/mcmc/pairwise_balance.h)
// evaluates, with the kernel's acceptance a(x -> y) (formed from the STATED densities) and the
// reference density as the density of the move actually sampled:
//   F = pi(x) c(x) T_ref(x -> y) a(x -> y),  B = pi(y) c(y) T_ref(y -> x) a(y -> x).
// F = B for all pairs iff the stated ratio equals the reference ratio: a density stated with a
// factor missing (a geometry term, the raster Jacobian) breaks the equality.
// Test pairs: with max_tries > 1, sample_move redraws (from the same uniform stream) moves whose
// destination has pi(y) = 0 (occluded connections, paths leaving the box), up to max_tries
// times. This only chooses WHICH pairs the pointwise identity F = B is evaluated on (pairs with
// flux), it does not enter F or B.
#pragma once

#include <functional>
#include <optional>
#include <utility>

#include <cmath>

#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/caustic_perturbation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/geometry/spawn.h"
#include "lib/path/dirac.h"

namespace tb::path_space {

inline double reference_density(const BidirectionalMutation& mut, const MltPath& x, const MltPath& y) {
  if (y.segments() < 1 || y.segments() > mut.max_segments()) return 0.0;
  const auto w = mut.way_between(x, y);
  if (!w) return 0.0;
  const double pd = mut.deletion_probability(x, w->l, w->m);
  const double pa = mut.addition_probability(x.segments(), w->kd(), w->ka);
  const auto splits = mut.valid_splits(x, *w);
  if (!(pd > 0.0) || !(pa > 0.0) || splits.empty()) return 0.0;
  const PathDensities d = path_densities(mut.context(), y.v, DiracPolicy::kCoefficient);
  double sum = 0.0;
  for (int s : splits) {
    if (!mut.split_connectible(y, w->l, s)) continue;
    double p = 1.0;
    for (int i = w->l + 1; i <= w->l + w->na(); ++i) p *= i <= w->l + s ? d.pL[i] : d.pE[i];
    sum += p;
  }
  return pd * pa * sum / static_cast<double>(splits.size());
}

inline double reference_density(const LensPerturbation& lens, const PathContext& ctx, const MltPath& x,
                                const MltPath& y) {
  const int k = x.segments();
  if (y.segments() != k || !lens.applicable(x) || !lens.applicable(y)) return 0.0;
  const int j = lens.chain_end(x);
  if (lens.chain_end(y) != j) return 0.0;
  for (int i = 0; i <= k; ++i)
    if ((i < j || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  const auto rx = path_raster(ctx, x), ry = path_raster(ctx, y);
  if (!rx || !ry) return 0.0;
  // The moved vertices y_j .. y_{k-1}, sampled from the camera with the lobes kept.
  const PathDensities d = path_densities(ctx, y.v, DiracPolicy::kCoefficientKeptLobe);
  double p = lens.kernel_density(*ry - *rx) * static_cast<double>(ctx.world->camera().pixel_count());
  for (int i = j; i <= k - 1; ++i) p *= d.pE[i];
  return p;
}

// Caustic perturbation: kernel at the angle from acos of the dot product, times |cos| / d^2 at
// y_{k-1} written out here (not through measure.h); the apex o is the mutation's.
inline double reference_density(const CausticPerturbation& c, const MltPath& x, const MltPath& y) {
  const int k = x.segments();
  if (y.segments() != k || !c.applicable(x) || !c.applicable(y)) return 0.0;
  const int j = c.chain_start(x);
  if (c.chain_start(y) != j) return 0.0;
  for (int i = 0; i <= k; ++i)
    if ((i <= j || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  if (!c.same_side(x, y.v[j + 1].hit.p)) return 0.0;
  const Vec3 a = c.apex(x), dx = x.v[j + 1].hit.p - a, dy = y.v[j + 1].hit.p - a;
  const double ly = glm::length(dy);
  const double cos_angle = glm::dot(dx, dy) / (glm::length(dx) * ly);
  const double theta = std::acos(std::clamp(cos_angle, -1.0, 1.0));
  double p = c.kernel_density(theta) * std::abs(glm::dot(y.v[j + 1].hit.ng, dy)) / (ly * ly * ly);
  // The vertices after the specular chain's vertices, sampled from the light side with lobes kept.
  const PathDensities d = path_densities(c.context(), y.v, DiracPolicy::kCoefficientKeptLobe);
  for (int i = j + 2; i <= k - 1; ++i) p *= d.pL[i];
  return p;
}

// Multi-chain perturbation: the lens part as above; below y_{k-1}, after a specular vertex the
// pE of path_densities(y, kept lobes), after a continued level the angular kernel at the acos of
// the directions' dot product times |cos| / d^2 written out here.
inline double reference_density(const MultiChainPerturbation& mc, const PathContext& ctx, const MltPath& x,
                                const MltPath& y) {
  const int k = x.segments();
  if (y.segments() != k) return 0.0;
  const std::vector<int> lx = mc.levels(x);
  if (lx.empty() || lx != mc.levels(y)) return 0.0;
  const int last = lx.back();
  for (int i = 0; i <= k; ++i)
    if ((i < last || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  const auto rx = path_raster(ctx, x), ry = path_raster(ctx, y);
  if (!rx || !ry) return 0.0;
  const PathDensities d = path_densities(ctx, y.v, DiracPolicy::kCoefficientKeptLobe);
  double p = mc.lens().kernel_density(*ry - *rx) * static_cast<double>(ctx.world->camera().pixel_count()) * d.pE[k - 1];
  for (int i = k - 1; i > last; --i) {
    if (is_dirac_surface(y.v[i])) {
      p *= d.pE[i - 1];
      continue;
    }
    const auto apex_dir = [&](const MltPath& z) {
      const Vec3 o = spawn_ray(z.v[i].hit, direction(z.v[i], z.v[i - 1])).o;
      return std::pair<Vec3, Vec3>{o, z.v[i - 1].hit.p - o};
    };
    const auto [ox, dx] = apex_dir(x);
    const auto [oy, dy] = apex_dir(y);
    const double ly = glm::length(dy);
    const double theta = std::acos(std::clamp(glm::dot(dx, dy) / (glm::length(dx) * ly), -1.0, 1.0));
    p *= mc.angular_density(theta) * std::abs(glm::dot(y.v[i - 1].hit.ng, dy)) / (ly * ly * ly);
  }
  return p;
}

// The reference density of a registered mutation (path_mutations.h): the independent assembly
// above for the four of Veach, the mutation's own stated density for any other (a mutation
// registered later is then checked for an acceptance consistent with what it states).
inline std::function<double(const MltPath&, const MltPath&)> reference_density_of(const PathMutation& m,
                                                                                 const PathContext& ctx) {
  if (auto* b = dynamic_cast<const PathProposalMutation<BidirectionalMutation>*>(&m))
    return [b](const MltPath& x, const MltPath& y) { return reference_density(b->proposal(), x, y); };
  if (auto* l = dynamic_cast<const PathProposalMutation<LensPerturbation>*>(&m))
    return [l, &ctx](const MltPath& x, const MltPath& y) { return reference_density(l->proposal(), ctx, x, y); };
  if (auto* c = dynamic_cast<const PathProposalMutation<CausticPerturbation>*>(&m))
    return [c](const MltPath& x, const MltPath& y) { return reference_density(c->proposal(), x, y); };
  if (auto* mc = dynamic_cast<const PathProposalMutation<MultiChainPerturbation>*>(&m))
    return [mc, &ctx](const MltPath& x, const MltPath& y) { return reference_density(mc->proposal(), ctx, x, y); };
  return [&m](const MltPath& x, const MltPath& y) { return m.density(x, y); };
}

// A registered mutation as a Proposal (for the generic checkers), with an optional test of where
// it can act (start paths of the pairwise checks).
struct MutationProposal {
  using State = MltPath;
  const PathMutation* m = nullptr;
  std::function<bool(const MltPath&)> can_act;
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const { return m->propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const { return m->density(x, y); }
  bool applicable(const MltPath& x) const { return can_act ? can_act(x) : m->weight(x) > 0.0; }
};

// K: a MetropolisHastings kernel; Ref: double(int component, const State& x, const State& y).
template <class K, class Ref>
class WithReferenceDensity {
 public:
  using State = typename K::State;
  using Move = typename K::Move;
  WithReferenceDensity(const K& kernel, Ref ref, int max_tries = 1)
      : k_(&kernel), ref_(std::move(ref)), max_tries_(max_tries) {}
  double target_density(const State& x) const { return k_->target_density(x); }
  std::optional<Move> sample_move(const State& x, Uniforms& u) const {
    std::optional<Move> m;
    for (int i = 0; i < max_tries_; ++i) {
      m = k_->sample_move(x, u);
      if (m && k_->target_density(k_->destination(*m)) > 0.0) return m;
    }
    return m;
  }
  const State& destination(const Move& m) const { return k_->destination(m); }
  Move reverse(const State& x, const Move& m) const { return k_->reverse(x, m); }
  double move_density(const State& x, const Move& m) const {
    const double c = k_->mixture().selection(m.component, x);
    return c > 0.0 ? c * ref_(m.component, x, m.y) : 0.0;
  }
  mcmc::MoveTerms move_terms(const State& x, const Move& m) const { return k_->move_terms(x, m); }
  double acceptance(const State& x, const Move& m) const { return k_->acceptance(x, m); }

 private:
  const K* k_;
  Ref ref_;
  int max_tries_;
};

}  // namespace tb::path_space

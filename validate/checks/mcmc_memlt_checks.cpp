// Registered checks of the manifold perturbation of manifold exploration (Jakob and Marschner
// 2012; lib/mcmc/path_space/manifold_perturbation.h) and of the integrator memlt:
//  - mcmc.memlt.pairwise.{caustic,dg_mirror_chain}: the perturbation alone in the renderer's
//    Metropolis-Hastings kernel, pi(x) T(x->y) a(x->y) = pi(y) T(y->x) a(y->x) to 1e-9 relative on
//    seeded BDPT pairs through specular chains, T the independent reference assembly
//    (manifold_broken.h: dense Eq. 11 determinant, Dirac factors recomputed); walk statistics;
//  - mcmc.memlt.mixture.pairwise.caustic: the integrator's kernel (bidirectional + manifold,
//    path-dependent selection) on BDPT pairs of any structure;
//  - mcmc.memlt.image.{caustic,dg_mirror_chain}: the memlt mixture through run_mlt against BDPT
//    (chains as Welch samples, compare_channels), alpha 1e-5.
// Negative controls (each passes when the broken variant is caught):
//  - mcmc.memlt.pairwise.caustic.no_geometry_term.negative_control and
//    mcmc.memlt.pairwise.caustic.transposed_block.negative_control: the acceptance from a T without
//    the generalised geometry term / with C_r = A_{r+1}^T, reference the correct T;
//  - mcmc.memlt.image.{caustic,dg_mirror_chain}.bidir_missing_geometry.negative_control: the memlt
//    mixture with the bidirectional density without its geometry term. Broken manifold densities
//    (no geometry term, its inverse, no lens Jacobian, no landing indicators) were NOT rejected
//    reliably by these image checks (docs/hslt.md, "Manifold exploration (memlt)"): the manifold
//    moves are local (r2 = 10 % of the image, below a pixel at 8 x 8) and a small share of the
//    mutations; their density is checked by the pairwise checks and the unit tests.
#include <functional>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/hash.h"
#include "lib/mcmc/path_space/manifold_perturbation.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "validate/mcmc/hslt_counters_json.h"
#include "validate/mcmc/manifold_broken.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/pairwise_record.h"
#include "validate/mcmc/path_space/mlt_image_check.h"
#include "validate/mcmc/path_space/reference_density.h"
#include "validate/mcmc/path_space/scene_cache.h"
#include "validate/registry.h"
#include "validate/render/broken_path_mutations.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

using namespace tb::path_space;
constexpr double kAlpha = 1e-5;
constexpr int kMaxDepth = 4;
constexpr int kRes = 16;

std::string walk_message(const HsltCounters& c) {
  const HsltCountsSnapshot s = snapshot(c);
  return fmt::format("{} proposals: {} converged walks ({:.2f} iterations each), {} non-reversible, {} generated",
                     s.proposals, s.converged, s.iterations_per_converged(), s.non_reversible, s.generated);
}

// ---- pairwise detailed balance ---------------------------------------------------------------
// The acceptance from `stated` (the mutation, or a broken copy), the reference the independent
// assembly of the correct T. Start paths: BDPT paths the perturbation applies to.
template <class P>
CheckResult pairwise_with(const CheckContext& cx, const std::string& name, const std::string& file, P stated,
                          bool broken, const std::shared_ptr<HsltCounters>& counters) {
  const LoadedScene& sc = cached_scene(file, kRes);
  const ManifoldPerturbation mp(sc.ctx);
  const auto mut = std::make_shared<const PathProposalMutation<P>>(
      "manifold", 1.0, std::move(stated), [](const P& p, const MltPath& x) { return p.applicable(x); });
  const PathMutation& m = *mut;
  const std::function<MltPath(Uniforms&)> start = [&sc, &mp](Uniforms& u) {
    MltPath any;
    for (int a = 0; a < 16384; ++a)
      if (auto p = sample_bdpt_path(sc.ctx, u, kMaxDepth, 3)) {
        if (mp.applicable(*p)) return *p;
        any = *p;
      }
    return any;
  };
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mcmc::SingleProposal(MutationProposal{&m, nullptr}));
  using K = decltype(kernel);
  const auto ref = [&mp](int, const MltPath& x, const MltPath& y) { return manifold_reference_density(mp, x, y); };
  // Up to 64 redraws per pair: on the caustic scene about half of the lens offsets leave the chain's
  // structure (the traced ray misses the sphere or the floor point's chain changes).
  const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, 64);
  const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(
      k, start, cx.size(300, 3000), cx.seed, hash_string(name));
  CheckResult res = pairwise_record(r, name);
  res.details["walks"] = counters_json(*counters);
  res.message = fmt::format("{}: {}; {}", file, res.message, walk_message(*counters));
  if (broken) {
    // Caught: some pair with flux violates balance against the correct T.
    res.passed = r.violations > 0 && r.live > 0;
    res.message = (res.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + res.message;
  }
  return res;
}

CheckResult manifold_pairwise(const CheckContext& cx, const std::string& name, const std::string& file) {
  const LoadedScene& sc = cached_scene(file, kRes);
  const auto counters = std::make_shared<HsltCounters>();
  return pairwise_with(cx, name, file, ManifoldPerturbation(sc.ctx, counters), false, counters);
}

CheckResult manifold_pairwise_broken(ManifoldBrokenDensity::Fault f, const CheckContext& cx, const std::string& name) {
  const LoadedScene& sc = cached_scene("caustic.json", kRes);
  const auto counters = std::make_shared<HsltCounters>();
  return pairwise_with(cx, name, "caustic.json", ManifoldBrokenDensity(ManifoldPerturbation(sc.ctx, counters), f), true,
                       counters);
}

// The integrator's kernel: make_memlt_mixture (bidirectional + manifold, c_j(x) normalised over the
// mutations that apply to x), the bidirectional T against its independent reference assembly, the
// manifold T against manifold_reference_density.
CheckResult mixture_pairwise(const CheckContext& cx, const std::string& name, const std::string& file) {
  const LoadedScene& sc = cached_scene(file, kRes);
  const auto counters = std::make_shared<HsltCounters>();
  PathMutationSettings ms;
  ms.max_segments = kMaxDepth + 1;
  const PathMixture mix(make_memlt_mixture(sc.ctx, ms, counters));
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mix);
  using K = decltype(kernel);
  const ManifoldPerturbation mp(sc.ctx);
  std::vector<std::function<double(const MltPath&, const MltPath&)>> refs;
  for (int j = 0; j < mix.components(); ++j)
    refs.push_back(mix.component(j).name() == "manifold"
                       ? std::function<double(const MltPath&, const MltPath&)>(
                             [&mp](const MltPath& x, const MltPath& y) { return manifold_reference_density(mp, x, y); })
                       : reference_density_of(mix.component(j), sc.ctx));
  const auto ref = [&refs](int j, const MltPath& x, const MltPath& y) { return refs[static_cast<size_t>(j)](x, y); };
  const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, 64);
  // Half of the start paths are BDPT paths the manifold perturbation applies to (they are rare on
  // the caustic scene), the others BDPT paths of any structure.
  const std::function<MltPath(Uniforms&)> start = [&sc, &mp](Uniforms& u) {
    const bool manifold = u.next() < 0.5;
    MltPath any;
    for (int a = 0; a < 16384; ++a)
      if (auto p = sample_bdpt_path(sc.ctx, u, kMaxDepth)) {
        if (!manifold || mp.applicable(*p)) return *p;
        any = *p;
      }
    return any;
  };
  const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(
      k, start, cx.size(400, 4000), cx.seed, hash_string(name));
  CheckResult res = pairwise_record(r, name);
  res.details["walks"] = counters_json(*counters);
  res.message = fmt::format("{}: {}; manifold: {}", file, res.message, walk_message(*counters));
  return res;
}

// ---- image: the memlt mixture against BDPT -------------------------------------------------------
// run_mlt over make_memlt_mixture on an 8 x 8 image at max depth 5, each chain one Welch sample,
// against BDPT (compare_channels: Šidák over pixels and channels, Stouffer, sum z^2), alpha 1e-5.
// broken: the bidirectional mutation's density without its geometry term.
CheckResult memlt_image(bool broken, const CheckContext& cx, const std::string& name, const std::string& file) {
  constexpr int kDepth = 5;
  const auto counters = std::make_shared<HsltCounters>();
  MltOptions o;
  o.mutations = [counters, broken](const PathContext& ctx, const PathMutationSettings& s) {
    PathMutationList l = make_memlt_mixture(ctx, s, counters);
    if (broken)
      l[0] = std::make_shared<const BidirWithoutGeometryTerm>(ctx, s.max_segments, find_path_mutation("bidirectional")->weight);
    return l;
  };
  CheckResult res = mlt_image_against_bdpt(cx, name, file, kDepth, o, broken, kAlpha, "manifold", [&counters, &file] {
    return fmt::format("{}: manifold {}", file, walk_message(*counters));
  });
  res.details["walks"] = counters_json(*counters);
  return res;
}

constexpr auto add = add_named_check;

const bool registered = [] {
  using Fault = ManifoldBrokenDensity::Fault;
  const std::string p = "mcmc.memlt.";
  add(p + "pairwise.caustic",
      "Manifold perturbation (Jakob and Marschner 2012) alone: pi T a symmetric to 1e-9 on seeded caustic-scene path "
      "pairs through the glass sphere, T the independent assembly (dense Eq. 11 determinant)",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return manifold_pairwise(cx, n, "caustic.json"); });
  add(p + "pairwise.dg_mirror_chain",
      "Manifold perturbation alone on dg-mirror-chain (specular chains of one or two curved mirrors): pi T a "
      "symmetric to 1e-9 on seeded path pairs",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return manifold_pairwise(cx, n, "dg-mirror-chain.json"); });
  add(p + "pairwise.caustic.no_geometry_term.negative_control",
      "Negative control: the acceptance from T without the generalised geometry term (|det J_S| and the Dirac "
      "factors) must violate pairwise balance against the correct T",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return manifold_pairwise_broken(Fault::kNoGeometryTerm, cx, n); });
  add(p + "pairwise.caustic.transposed_block.negative_control",
      "Negative control: the acceptance from T with the chain Jacobian assembled with C_r = A_{r+1}^T must violate "
      "pairwise balance against the correct T",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return manifold_pairwise_broken(Fault::kTransposedBlock, cx, n); });
  add(p + "mixture.pairwise.caustic",
      "The memlt integrator's kernel (bidirectional + manifold, path-dependent selection): pi c T a symmetric to 1e-9 "
      "on seeded caustic-scene BDPT pairs, each T against its reference assembly",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return mixture_pairwise(cx, n, "caustic.json"); });
  add(p + "image.caustic",
      "Integrator memlt's mixture (run_mlt; >= 48 chains as Welch samples) against BDPT on the 8 x 8 caustic scene at "
      "max depth 5 (Welch t, Stouffer, sum z^2, alpha 1e-5)",
      CheckKind::kStatistical,
      [](const CheckContext& cx, const std::string& n) { return memlt_image(false, cx, n, "caustic.json"); });
  add(p + "image.dg_mirror_chain",
      "Integrator memlt's mixture against BDPT on the 8 x 8 dg-mirror-chain scene at max depth 5 (alpha 1e-5)",
      CheckKind::kStatistical,
      [](const CheckContext& cx, const std::string& n) { return memlt_image(false, cx, n, "dg-mirror-chain.json"); });
  add(p + "image.caustic.bidir_missing_geometry.negative_control",
      "Negative control: the caustic image check must reject the memlt mixture with the bidirectional density stated "
      "without its geometry term",
      CheckKind::kStatistical,
      [](const CheckContext& cx, const std::string& n) { return memlt_image(true, cx, n, "caustic.json"); });
  add(p + "image.dg_mirror_chain.bidir_missing_geometry.negative_control",
      "Negative control: the dg-mirror-chain image check must reject the memlt mixture with the bidirectional density "
      "stated without its geometry term",
      CheckKind::kStatistical,
      [](const CheckContext& cx, const std::string& n) { return memlt_image(true, cx, n, "dg-mirror-chain.json"); });
  return true;
}();

}  // namespace
}  // namespace tb

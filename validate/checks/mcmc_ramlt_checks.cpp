// Checks of regional adaptive MLT (Otsu et al., "Regional Adaptive Metropolis Light Transport";
// lib/mcmc/path_space/ramlt_*.h, docs/ramlt.md):
//  - mcmc.ramlt.{lens,multichain}.pairwise: pi(x) T(x->y) a(x->y) = pi(y) T(y->x) a(y->x) to 1e-9
//    relative on seeded path pairs at FROZEN per-region lambda (an 8 x 8 (lens) or 64 x 64 (multi-chain: quarter-pixel cells) screen grid on the 16 x 16
//    image, lambda_k spread over [-9, -5] so that neighbouring regions differ), the acceptance from
//    the stated T (sigma of x's region forward, of y's region reverse, Otsu Eq. 2-3) and the flux
//    from the unbroken perturbation's density; the fraction of pairs whose y lies in another region
//    than x is measured and must be >= 20% (deterministic);
//  - mcmc.ramlt.direction.chi2: the truncated-normal direction kernel (Otsu Sec. 3) sampled around
//    a fixed direction against its stated density per solid angle times sin(theta), on (theta, phi),
//    at sigma = 0.02, 0.3, 2.5, and the realised primary direction of the ramlt-lens proposal from a
//    Cornell-box path at its region's sigma; alpha = 1e-5, Šidák over the four;
//  - mcmc.ramlt.lens.image.cornell: run_ramlt (ramlt-lens, 20 x 20 grid, Otsu Sec. 8.1 defaults)
//    on the 8 x 8 Cornell box at max depth 3, >= 48 chains as Welch samples, against BDPT
//    (compare_channels: Šidák over pixels and channels, Stouffer, sum z^2), alpha = 1e-5;
//  - mcmc.ramlt.lens_quadtree.image.cornell: the same with the quadtree partition (Otsu Sec. 6.2),
//    refined every 65536 mutations, leaves with > 500 reports split;
//  - mcmc.ramlt.multichain.image.caustic_grouped: run_ramlt (multi-chain) on the 16 x 16 caustic scene
//    at depth 10 against BDPT over pixel groups (as mlt.path_space.image.caustic_grouped); the
//    multi-chain perturbation makes about 1% of the proposals there, the rest are bidirectional;
//  - negative controls, passing when the broken variant IS rejected (validate/render/broken_ramlt.h):
//    the reverse density evaluated with the region of x instead of y (pairwise, lens and
//    multi-chain), the angle density without its truncation mass (chi-square), and the image checks
//    (grid, quadtree, grouped caustic) with the bidirectional density missing a geometry term (validate/render/broken_path_mutations.h).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <type_traits>
#include <utility>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/ramlt.h"
#include "lib/mcmc/path_space/ramlt_direction.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/light_sampler.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/pairwise_record.h"
#include "validate/mcmc/path_space/reference_density.h"
#include "validate/registry.h"
#include "validate/render/broken_path_mutations.h"
#include "validate/render/broken_ramlt.h"
#include "validate/render/pixel_groups.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"
#include "validate/mcmc/path_space/scene_cache.h"

namespace tb {
namespace {

using namespace tb::path_space;
constexpr double kAlpha = 1e-5;
constexpr int kMaxDepth = 4;
constexpr int kRes = 16;

using SceneCtx = LoadedScene;
const SceneCtx& scene(const std::string& file) { return cached_scene(file, kRes); }

CheckResult negate(CheckResult inner) {
  inner.passed = !inner.passed;
  inner.message =
      (inner.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + inner.message;
  return inner;
}

// Frozen scales on an n x n screen grid: lambda_k = -9 + 4 frac(0.618 k + 0.3), sigma in [0.011,
// 0.082] rad, about 0.5 to 4 pixels of the 16 x 16 image (a cell is 16 / n pixels).
RegionalScale frozen_scale(const PathContext& ctx, int n) {
  auto p = ScreenPartition::make(ctx, "grid", n);
  std::vector<double> lambda(static_cast<size_t>(p->regions()));
  for (size_t k = 0; k < lambda.size(); ++k) {
    const double f = 0.618034 * static_cast<double>(k) + 0.3;
    lambda[k] = -9.0 + 4.0 * (f - std::floor(f));
  }
  return {std::move(p), std::make_shared<const std::vector<double>>(std::move(lambda))};
}

// The 4d partition (Otsu Sec. 5.4, Eq. 7; Sec. 6.3) of the multi-chain perturbation, frozen:
// sigma_1 on an n x n screen grid as frozen_scale, sigma_2 per 4d region lambda2_k = -10 + 4
// frac(0.618 k + 0.7), so that lambda_1 != lambda_2 in general. "grid4d": n_bottom x n_bottom
// direction cells; "quadtree4d": every cell's direction quadtree split non-uniformly (root, then
// its first child twice: 10 leaves of three sizes).
RegionalScale frozen_scale_4d(const PathContext& ctx, const std::string& name, int n, int n_bottom) {
  RegionalScale s = frozen_scale(ctx, n);
  std::shared_ptr<const Screen4dPartition> p2;
  if (name == "quadtree4d") {
    auto t = std::make_shared<mcmc::GridQuadtreePartition>(std::array<double, 4>{0.0, 0.0, 0.0, 0.0},
                                                           std::array<double, 4>{1.0, 1.0, 1.0, 1.0}, n);
    for (int l = 0; l < t->cells(); ++l) {
      t->split(l);
      t->split(l);
      t->split(l);
    }
    p2 = std::make_shared<const Screen4dPartition>(ctx, t);
  } else {
    p2 = Screen4dPartition::make(ctx, name, n, n_bottom);
  }
  std::vector<double> lambda2(static_cast<size_t>(p2->regions()));
  for (size_t k = 0; k < lambda2.size(); ++k) {
    const double f = 0.618034 * static_cast<double>(k) + 0.7;
    lambda2[k] = -10.0 + 4.0 * (f - std::floor(f));
  }
  s.partition2 = p2;
  s.lambda2 = std::make_shared<const std::vector<double>>(std::move(lambda2));
  return s;
}

enum class Fault { kNone, kDestinationScale, kWithoutSigma2 };

// Pairwise balance of one regional adaptive perturbation (alone), flux from the unbroken density.
// The check is valid only when >= 20% of the pairs with pi(y) > 0 cross a region boundary: the
// positive check passes when it is valid and balanced, the negative control when it is valid and
// NOT balanced (a control that is not exercised is not caught).
// With a 4d partition (scale.partition2) a pair crosses when x and y lie in different 4d regions.
template <class P>
CheckResult ramlt_pairwise(Fault fault, const CheckContext& cx, const std::string& name, const std::string& file,
                           int grid, int max_tries, const std::string& partition4d = "") {
  const SceneCtx& sc = scene(file);
  const RegionalScale scale = partition4d.empty() ? frozen_scale(sc.ctx, grid) : frozen_scale_4d(sc.ctx, partition4d, grid, 50);
  const auto correct = std::make_shared<const RamltMutation<P>>(name, 1.0, P(sc.ctx, scale));
  std::shared_ptr<const PathMutation> m = correct;
  if (fault == Fault::kDestinationScale) m = std::make_shared<const RamltDestinationScale<P>>(correct);
  if constexpr (std::is_same_v<P, RamltMultiChainPerturbation>)
    if (fault == Fault::kWithoutSigma2) m = std::make_shared<const RamltMultiChainWithoutSigma2>(correct);
  const PathMutation& mut = *m;
  const std::function<MltPath(Uniforms&)> start = [&sc, &mut](Uniforms& u) {
    MltPath any;
    for (int a = 0; a < 4096; ++a)
      if (auto p = sample_bdpt_path(sc.ctx, u, kMaxDepth)) {
        if (mut.weight(*p) > 0.0) return *p;
        any = *p;
      }
    return any;
  };
  const auto kernel = mcmc::MetropolisHastings(PathTarget{&sc.ctx}, mcmc::SingleProposal(MutationProposal{&mut, nullptr}));
  using K = decltype(kernel);
  const auto ref = [&correct](int, const MltPath& x, const MltPath& y) { return correct->density(x, y); };
  const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, max_tries);
  const int64_t pairs = cx.size(400, 4000);
  const uint64_t key = hash_string(name);
  const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(k, start, pairs, cx.seed, key);
  CheckResult res = pairwise_record(r, name);
  // Which pairs cross a region boundary: the same draws as the checker (same streams).
  std::vector<int> cross(static_cast<size_t>(pairs), 0), live(static_cast<size_t>(pairs), 0);
  parallel_for(static_cast<size_t>(pairs), [&](size_t i) {
    Rng rng = Rng::for_sample(cx.seed, key, i);
    RngUniforms u(rng);
    const MltPath x = start(u);
    const auto mv = k.sample_move(x, u);
    if (!mv || !(k.target_density(mv->y) > 0.0)) return;
    live[i] = 1;
    cross[i] = scale.partition2 ? scale.region2(x) != scale.region2(mv->y) : scale.region(x) != scale.region(mv->y);
  });
  int64_t n_cross = 0, n_live = 0;
  for (size_t i = 0; i < cross.size(); ++i) {
    n_cross += cross[i];
    n_live += live[i];
  }
  const double frac = n_live > 0 ? static_cast<double>(n_cross) / static_cast<double>(n_live) : 0.0;
  res.details["pairs_across_regions"] = n_cross;
  res.details["fraction_across_regions"] = frac;
  res.message = fmt::format("{}, {} x {} grid{}: {}; {} of {} proposed pairs with pi(y) > 0 cross a region boundary "
                            "({:.0f}%)", file, grid, grid, partition4d.empty() ? "" : " x direction (" + partition4d + ")",
                            res.message, n_cross, n_live, 100.0 * frac);
  const bool exercised = frac >= 0.2;
  res.details["exercised"] = exercised;
  if (!exercised) res.message += " (< 20%: the check does not exercise region boundaries, NOT VALID)";
  if (fault == Fault::kNone) {
    res.passed = r.passed && exercised;
    return res;
  }
  // Negative control: caught when valid and unbalanced.
  res.passed = exercised && !r.passed;
  res.message = (res.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + res.message;
  return res;
}

CheckResult lens_pairwise(Fault f, const CheckContext& cx, const std::string& n) {
  return ramlt_pairwise<RamltLensPerturbation>(f, cx, n, "cornell-box.json", 8, 8);
}
// Multi-chain paths (D S+ D ...) exist on the glass scenes only; the continued direction often
// misses the specular object: up to 64 redraws per pair.
CheckResult multichain_pairwise(Fault f, const CheckContext& cx, const std::string& n) {
  return ramlt_pairwise<RamltMultiChainPerturbation>(f, cx, n, "caustic.json", 64, 64);
}

// The multi-chain perturbation on the 4d partitions (sigma_1 per screen cell, sigma_2 per 4d
// region): grid4d and quadtree4d, both must pass. The negative controls run on grid4d.
CheckResult multichain_4d_pairwise(Fault f, const CheckContext& cx, const std::string& n) {
  if (f != Fault::kNone) return ramlt_pairwise<RamltMultiChainPerturbation>(f, cx, n, "caustic.json", 64, 64, "grid4d");
  CheckResult a = ramlt_pairwise<RamltMultiChainPerturbation>(f, cx, n, "caustic.json", 64, 64, "grid4d");
  const CheckResult b = ramlt_pairwise<RamltMultiChainPerturbation>(f, cx, n + ".quadtree4d", "caustic.json", 64, 64,
                                                                    "quadtree4d");
  a.passed = a.passed && b.passed;
  a.samples += b.samples;
  a.statistic = std::max(a.statistic, b.statistic);
  a.details["quadtree4d"] = b.details;
  a.message = a.message + " | " + b.message;
  return a;
}

// ---- the direction kernel against its stated density ----------------------------------------------
using AngleDensity = double (*)(double, double);

// One chi-square run on (theta, phi) of directions w' around w: stated density per dtheta dphi =
// p_w sin(theta) = p_theta / (2 pi) (ramlt_direction.h). sample(u) returns w' or nothing.
template <class Sample>
SamplerChi2Result direction_run(const Vec3& w, double sigma, AngleDensity stated, Sample&& sample, int64_t samples,
                                uint64_t seed, uint64_t key) {
  const Frame fr = Frame::from_z(w);
  const double tmax = std::min(kPi, 10.0 * sigma);  // mass beyond 10 sigma < 1e-22
  SamplerChi2Options o;
  o.samples = samples;
  o.seed = seed;
  o.key = key;
  return chi2_test(
      Chi2Domain::rectangle(Vec2(0.0, 0.0), Vec2(tmax, 2.0 * kPi), 40, 24),
      [&](Uniforms& u) -> std::optional<Vec2> {
        const std::optional<Vec3> wy = sample(u);
        if (!wy) return std::nullopt;
        const Vec3 l = fr.to_local(*wy);
        double phi = std::atan2(l.y, l.x);
        if (phi < 0) phi += 2.0 * kPi;
        return Vec2(std::atan2(std::sqrt(l.x * l.x + l.y * l.y), l.z), phi);
      },
      [&](const Vec2& q) { return stated(q.x, sigma) / (2.0 * kPi); }, o);
}

// The kernel alone at sigma = 0.02, 0.3, 2.5 around a fixed w; and the regional adaptive lens
// perturbation's realised primary direction on the 16 x 16 Cornell box, from a central path whose
// region's sigma (0.002 (1 + k mod 7) rad on an 8 x 8 grid: neighbouring regions differ) is the
// one stated, so a proposal reading another region's scale is seen. Its moves stay on the image
// (sigma <= 0.014 rad, the image half-width is about 0.17 rad).
CheckResult direction_chi2(AngleDensity stated, const CheckContext& cx, const std::string& name) {
  const int64_t samples = cx.size(100000, 1000000);
  std::vector<std::pair<std::string, SamplerChi2Result>> runs;
  const Vec3 w = glm::normalize(Vec3(0.3, -0.5, 0.8));
  for (double sigma : {0.02, 0.3, 2.5})
    runs.emplace_back(fmt::format("kernel sigma = {}", sigma),
                      direction_run(
                          w, sigma, stated,
                          [&](Uniforms& u) -> std::optional<Vec3> { return TruncatedNormalDirection::sample(w, u.next2(), sigma); },
                          samples, cx.seed, hash_values(hash_string(name), static_cast<uint64_t>(sigma * 1000))));
  const SceneCtx& sc = scene("cornell-box.json");
  auto part = ScreenPartition::make(sc.ctx, "grid", 8);
  std::vector<double> lambda(static_cast<size_t>(part->regions()));
  for (size_t k = 0; k < lambda.size(); ++k) lambda[k] = 2.0 * std::log(0.002 * static_cast<double>(1 + k % 7));
  const RegionalScale scale{part, std::make_shared<const std::vector<double>>(lambda)};
  const RamltLensPerturbation lens(sc.ctx, scale);
  Rng rng = Rng::for_sample(cx.seed, hash_string(name + ".x"), 0);
  RngUniforms ux(rng);
  MltPath x;
  for (int a = 0; a < 100000; ++a) {
    const auto p = sample_bdpt_path(sc.ctx, ux, kMaxDepth);
    if (!p || !lens.applicable(*p)) continue;
    const auto r = path_raster(sc.ctx, *p);
    if (r && std::abs(r->x - 8.0) < 2.0 && std::abs(r->y - 8.0) < 2.0) {
      x = *p;
      break;
    }
  }
  if (x.v.empty()) {
    CheckResult res;
    res.passed = false;
    res.message = "no central Cornell-box path the lens perturbation applies to";
    return res;
  }
  const Vec3 wx = RamltLensPerturbation::primary_direction(x);
  const double sigma_x = scale.sigma(x);
  runs.emplace_back(fmt::format("ramlt-lens on cornell-box.json, region {} sigma = {:.3g}", scale.region(x), sigma_x),
                    direction_run(
                        wx, sigma_x, stated,
                        [&](Uniforms& u) -> std::optional<Vec3> {
                          const auto y = lens.propose(x, u);
                          if (!y) return std::nullopt;
                          return RamltLensPerturbation::primary_direction(*y);
                        },
                        samples, cx.seed, hash_string(name + ".lens")));
  const double alpha_each = 1.0 - std::pow(1.0 - kAlpha, 1.0 / static_cast<double>(runs.size()));  // Šidák
  CheckResult res;
  res.passed = true;
  res.statistic_name = "min p";
  res.statistic = 1.0;
  res.alpha = alpha_each;
  std::string msg;
  for (const auto& [label, r] : runs) {
    // A failed proposal would leave the stated density unnormalised on the realised samples.
    res.passed = res.passed && r.passed(alpha_each) && r.failed == 0;
    res.statistic = std::min(res.statistic, r.p_value());
    res.samples += r.samples;
    res.details[label] = r.details();
    msg += fmt::format("{}{}: {}", msg.empty() ? "" : "; ", label, r.message());
  }
  res.p_value = res.statistic;
  res.message = "truncated-normal direction (theta, phi): " + msg;
  return res;
}

// ---- image: run_ramlt against BDPT ------------------------------------------------------------------
CheckResult image_check(const RamltOptions& opt, const CheckContext& cx, const std::string& name) {
  const std::unique_ptr<World> world = load_scene_at_resolution("cornell-box.json", 8, 8);
  Film ref(8, 8);
  RenderSettings rs;
  rs.spp = cx.size(2048, 8192);
  rs.passes = 32;
  rs.max_depth = 3;
  rs.seed = hash_values(cx.seed, hash_string(name + ".bdpt"));
  render_bdpt(*world, rs, ref);
  Film film(8, 8);
  RenderSettings st;
  st.passes = cx.size(48, 128);
  st.spp = st.passes * 160;
  st.max_depth = 3;
  st.seed = hash_values(cx.seed, hash_string(name));
  const RamltStats s = run_ramlt(*world, st, film, opt);
  const ChannelCompare c = compare_channels(film.welch(), ref.welch(), kAlpha);
  CheckResult res;
  res.passed = !c.rejects();
  res.statistic_name = "p (Šidák over pixel channels)";
  res.statistic = c.p_value();
  res.p_value = c.p_value();
  res.alpha = kAlpha;
  res.samples = s.mlt.mutations_total;
  int64_t updates = 0;
  for (int u : s.maps.updates) updates += u;
  res.message = fmt::format(
      "{} chains x {} mutations ({} batches, last {} steps; {} regions, {} refinements; {} lambda updates) against "
      "BDPT: {}",
      s.mlt.chains, s.mlt.mutations_total / std::max<int64_t>(1, s.mlt.chains), s.batches, s.batch_steps, s.maps.regions,
      s.maps.refinements, updates, c.message());
  res.details = c.details();
  for (const auto& m : s.mlt.mutations) res.details["acceptance_" + m.name] = m.acceptance_rate();
  res.details["lambda_updates"] = updates;
  return res;
}

// The quadtree variant of the image check: refinements every 65536 mutations (about 7 in the quick run).
RamltOptions quadtree() {
  RamltOptions o;
  o.partition = "quadtree";
  o.refine_every = 65536;
  o.split_threshold = 500;
  return o;
}

RamltOptions multichain() {
  RamltOptions o;
  o.perturbation = RamltPerturbation::kMultiChain;
  return o;
}

// The driver's bidirectional mutation replaced by the one without geometry term (same weight and
// maximum length; validate/render/broken_path_mutations.h).
PathMutationList without_geometry_term(PathMutationList l) {
  const auto& b = dynamic_cast<const PathProposalMutation<BidirectionalMutation>&>(*l[0]);
  l[0] = std::make_shared<const BidirWithoutGeometryTerm>(b.proposal().context(), b.proposal().max_segments(),
                                                          b.base_weight());
  return l;
}

// ---- image by pixel groups: run_ramlt (multi-chain) against BDPT on the 16 x 16 caustic scene ----
// As mlt.path_space.image.caustic_grouped (mcmc_path_space_checks.cpp): sums over pixel groups
// holding >= 16 expected chain starts each (grouping from a separate pilot BDPT image), each chain's
// group sums one Welch sample, 1024 chains (4096 full) x 1024 mutations, the scene's max depth.
CheckResult grouped_image_check(const RamltOptions& opt, const CheckContext& cx, const std::string& name,
                                const std::string& file) {
  constexpr int kGroupRes = 16;
  constexpr double kStartsPerGroup = 16.0;
  const std::unique_ptr<World> world = load_scene_at_resolution(file, kGroupRes, kGroupRes);
  const int max_depth = world->integrator_defaults().value("max_depth", 8);
  const int64_t chains = cx.size(1024, 4096);
  RenderSettings rs;
  rs.max_depth = max_depth;
  Film pilot(kGroupRes, kGroupRes);
  rs.spp = 256;
  rs.passes = 8;
  rs.seed = hash_values(cx.seed, hash_string(name + ".pilot"));
  render_bdpt(*world, rs, pilot);
  GroupedWelch ref_groups(
      group_pixels_by_share(pilot.mean_image(), kGroupRes, kGroupRes, kStartsPerGroup / double(chains)));
  GroupedWelch groups(ref_groups.groups());
  Film ref(kGroupRes, kGroupRes);
  ref_groups.attach(ref);
  rs.spp = cx.size(1024, 4096);
  rs.passes = 32;
  rs.seed = hash_values(cx.seed, hash_string(name + ".bdpt"));
  render_bdpt(*world, rs, ref);
  ref_groups.detach(ref);
  Film film(kGroupRes, kGroupRes);
  groups.attach(film);
  RenderSettings st;
  st.passes = chains;
  st.spp = chains * 1024 / (kGroupRes * kGroupRes);
  st.max_depth = max_depth;
  st.seed = hash_values(cx.seed, hash_string(name));
  const RamltStats s = run_ramlt(*world, st, film, opt);
  groups.detach(film);
  const ChannelCompare c = compare_channels(groups.welch(), ref_groups.welch(), kAlpha);
  CheckResult res;
  res.passed = !c.rejects();
  res.statistic_name = "p (Šidák over pixel-group channels)";
  res.statistic = c.p_value();
  res.p_value = c.p_value();
  res.alpha = kAlpha;
  res.samples = s.mlt.mutations_total;
  res.message = fmt::format("{} chains x {} mutations against BDPT (max depth {}), {} pixel groups: {}", s.mlt.chains,
                            s.mlt.mutations_total / std::max<int64_t>(1, s.mlt.chains), max_depth,
                            group_count(ref_groups.groups()), c.message());
  res.details = c.details();
  for (const auto& m : s.mlt.mutations) {
    res.details[fmt::format("acceptance_{}", m.name)] = m.acceptance_rate();
    res.details[fmt::format("proposed_{}", m.name)] = m.proposed;
  }
  return res;
}

// ---- adaptation in the renderer: median acceptance at a*, diminishing steps, initial lambda ------
// One adapting run of run_ramlt (ramlt-lens, Sec. 8.1 adaptation defaults) on the Cornell box at
// max depth 3, `chains` x `per_chain` mutations, with the screen-level record kept.
RamltStats adapting_run(RamltOptions o, const std::string& name, uint64_t seed, int res, int64_t chains,
                        int64_t per_chain) {
  const std::unique_ptr<World> world = load_scene_at_resolution("cornell-box.json", res, res);
  Film film(res, res);
  RenderSettings st;
  st.passes = chains;
  st.spp = std::max<int64_t>(1, chains * per_chain / (static_cast<int64_t>(res) * res));
  st.max_depth = 3;
  st.seed = hash_values(seed, hash_string(name));
  o.keep_record = true;
  return run_ramlt(*world, st, film, o);
}

// Otsu Eq. 5 moves lambda_k by gamma sgn(a_hat_k - a*): at equilibrium as many batches lie above a*
// as below, i.e. the MEDIAN of the batch acceptance a_hat_k (Eq. 4, L = 10 reports) is a* (its
// mean need not be). Per region with >= 400 batches, over the second half of its batches: exact
// two-sided binomial sign test of #(a_hat > a*) among the batches != a* against 1/2, Šidák over
// the tested regions at alpha 1e-5; and diminishing adaptation (Eq. 6): every |lambda_j -
// lambda_{j-1}| over the last 10% of the region's updates <= 0.25 (gamma_j = 5 j^-1/2 <= 0.25 for
// j >= 400; tested in regions with >= 450 updates). At least min(8, regions) regions must be
// tested. Cornell box 16 x 16, 4 x 4 grid, 32 chains x 16384 mutations (full: 64 x 32768).
CheckResult adaptation_target_check(RamltOptions o, const CheckContext& cx, const std::string& name) {
  if (o.partition == "grid") o.grid = 4;
  const RamltStats s = adapting_run(o, name, cx.seed, 16, cx.size(32, 64), cx.size(16384, 32768));
  const double a_star = o.adaptation.target_acceptance;
  std::map<int, std::vector<const mcmc::AdaptationUpdateRecord*>> by_region;
  for (const auto& r : s.record) by_region[r.region].push_back(&r);
  int tested = 0, tested_steps = 0;
  double min_p = 1.0, max_late_step = 0.0, mean_sum = 0.0, median_sum = 0.0;
  std::string worst;
  int64_t batches = 0;
  std::vector<double> ps;
  for (const auto& [region, rec] : by_region) {
    const size_t n = rec.size();
    if (n < 400) continue;
    int64_t above = 0, decided = 0;
    std::vector<double> late;
    for (size_t i = n / 2; i < n; ++i) {
      const double a = rec[i]->a_hat;
      late.push_back(a);
      if (a == a_star) continue;
      ++decided;
      above += a > a_star;
    }
    batches += static_cast<int64_t>(late.size());
    const double p = stats::binomial_test(above, decided, 0.5).p_value;
    ps.push_back(p);
    std::sort(late.begin(), late.end());
    const double median = late[late.size() / 2];
    double mean = 0.0;
    for (double a : late) mean += a;
    mean /= static_cast<double>(late.size());
    mean_sum += mean;
    median_sum += median;
    if (p < min_p) {
      min_p = p;
      worst = fmt::format("region {}: {} of {} above a*, median {:.3f}, mean {:.3f}", region, above, decided, median, mean);
    }
    ++tested;
    // Diminishing steps over the last 10% of the updates (records with j > 0 are updates).
    if (rec.back()->j >= 450) {
      ++tested_steps;
      for (size_t i = std::max<size_t>(1, n - n / 10); i < n; ++i)
        max_late_step = std::max(max_late_step, std::abs(rec[i]->lambda - rec[i - 1]->lambda));
    }
  }
  const int need = std::min(8, s.maps.regions);
  const double alpha_each = tested > 0 ? 1.0 - std::pow(1.0 - kAlpha, 1.0 / tested) : kAlpha;
  CheckResult res;
  res.statistic_name = "min p (sign test)";
  res.statistic = min_p;
  res.p_value = tested > 0 ? std::min(1.0, 1.0 - std::pow(1.0 - min_p, tested)) : 0.0;
  res.alpha = kAlpha;
  res.samples = batches;
  const bool sign_ok = tested >= need && min_p >= alpha_each;
  const bool steps_ok = tested_steps == 0 || max_late_step <= 0.25;
  res.passed = sign_ok && steps_ok && tested_steps >= (s.maps.regions > 1 || o.partition != "fixed" ? need : 0);
  res.message = fmt::format(
      "{} ({} regions, {} mutations): {} regions with >= 400 batches, sign test of the batch acceptance against a* = "
      "{}: min p {:.3g} (Šidák alpha each {:.2g}; {}); mean over regions of the late median {:.3f}, of the late mean "
      "{:.3f}; {} regions with >= 450 updates, max |delta lambda| over their last 10% of updates {:.3f} (bound 0.25)",
      o.partition, s.maps.regions, s.mlt.mutations_total, tested, a_star, min_p, alpha_each, worst,
      tested > 0 ? median_sum / tested : 0.0, tested > 0 ? mean_sum / tested : 0.0, tested_steps, max_late_step);
  if (tested < need) res.message += fmt::format(" (fewer than {} regions tested: NOT VALID)", need);
  res.details["regions_tested"] = tested;
  res.details["regions_tested_steps"] = tested_steps;
  res.details["max_late_step"] = max_late_step;
  res.details["min_p"] = min_p;
  res.details["late_median_mean"] = tested > 0 ? median_sum / tested : 0.0;
  res.details["late_mean_mean"] = tested > 0 ? mean_sum / tested : 0.0;
  return res;
}

// Initial-lambda insensitivity: lambda0 in {-10, -5, 0, 1, 5} (each its own seed) end at the same
// per-region lambda. Reference: S = 4 further runs at lambda0 = 1 (other seeds) give per region
// the mean m_r and a pooled standard deviation s (over regions, S - 1 dof each); every final
// lambda_r(lambda0) must lie within m_r +- 5 s sqrt(1 + 1 / S) (five standard deviations of a
// new run's deviation from the seed mean). Cornell box 8 x 8, 2 x 2 grid, 16 chains x 4096
// mutations (full: 32 x 8192); about 800 updates per region.
CheckResult initial_lambda_check(RamltOptions o, const CheckContext& cx, const std::string& name) {
  o.grid = 2;
  const int64_t chains = cx.size(16, 32), per_chain = cx.size(4096, 8192);
  constexpr int kSeeds = 4;
  const std::vector<double> starts{-10.0, -5.0, 0.0, 1.0, 5.0};
  std::vector<std::vector<double>> ref(kSeeds), runs(starts.size());
  parallel_for(kSeeds + starts.size(), [&](size_t i) {
    RamltOptions oi = o;
    if (i < kSeeds) {
      oi.adaptation.lambda0 = 1.0;
      ref[i] = adapting_run(oi, name + ".seed", hash_values(cx.seed, i), 8, chains, per_chain).maps.lambda;
    } else {
      oi.adaptation.lambda0 = starts[i - kSeeds];
      runs[i - kSeeds] = adapting_run(oi, name, hash_values(cx.seed, i), 8, chains, per_chain).maps.lambda;
    }
  });
  const size_t R = ref[0].size();
  std::vector<double> m(R, 0.0);
  double ss = 0.0;
  for (size_t r = 0; r < R; ++r) {
    for (const auto& l : ref) m[r] += l[r] / kSeeds;
    for (const auto& l : ref) ss += (l[r] - m[r]) * (l[r] - m[r]);
  }
  const double sd = std::sqrt(ss / static_cast<double>(R * (kSeeds - 1)));
  const double tol = 5.0 * sd * std::sqrt(1.0 + 1.0 / kSeeds);
  double worst = 0.0;
  std::string worst_at, finals;
  for (size_t i = 0; i < starts.size(); ++i) {
    finals += fmt::format("{}lambda0 {}: [", i ? "; " : "", starts[i]);
    for (size_t r = 0; r < R; ++r) {
      const double d = std::abs(runs[i][r] - m[r]);
      finals += fmt::format("{}{:.2f}", r ? ", " : "", runs[i][r]);
      if (d > worst) {
        worst = d;
        worst_at = fmt::format("lambda0 {}, region {}", starts[i], r);
      }
    }
    finals += "]";
  }
  std::string means;
  for (size_t r = 0; r < R; ++r) means += fmt::format("{}{:.2f}", r ? ", " : "", m[r]);
  CheckResult res;
  res.passed = R > 1 && worst <= tol && sd > 0.0;
  res.statistic_name = "max |lambda_r(lambda0) - m_r|";
  res.statistic = worst;
  res.samples = static_cast<int64_t>(kSeeds + starts.size()) * chains * per_chain;
  res.message = fmt::format(
      "{} regions; seed mean m_r [{}] over {} seeds, pooled sd {:.3f}, tolerance 5 sd sqrt(1 + 1/{}) = {:.3f}; final "
      "lambda {}; max deviation {:.3f} ({})",
      R, means, kSeeds, sd, kSeeds, tol, finals, worst, worst_at);
  res.details["tolerance"] = tol;
  res.details["pooled_sd"] = sd;
  res.details["max_deviation"] = worst;
  return res;
}

constexpr auto add = add_named_check;

const bool registered = [] {
  const std::string p = "mcmc.ramlt.";
  add(p + "lens.pairwise",
      "Regional adaptive lens perturbation (Otsu Sec. 3, Eq. 2-3) at frozen per-region lambda: pi T a symmetric to "
      "1e-9 on Cornell-box path pairs, >= 20% of them across region boundaries",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) { return lens_pairwise(Fault::kNone, cx, n); });
  add(p + "multichain.pairwise",
      "Regional adaptive multi-chain perturbation at frozen per-region lambda: pi T a symmetric to 1e-9 on caustic "
      "paths D S+ D ..., >= 20% of them across region boundaries",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return multichain_pairwise(Fault::kNone, cx, n); });
  add(p + "multichain_4d.pairwise",
      "Regional adaptive multi-chain perturbation on the 4d partitions grid4d and quadtree4d (Otsu Sec. 5.4, Eq. 7, "
      "Sec. 6.3) at frozen lambda_1 (screen cell) != lambda_2 (4d region): pi T a symmetric to 1e-9 on caustic paths, "
      ">= 20% of them across 4d region boundaries",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return multichain_4d_pairwise(Fault::kNone, cx, n); });
  add(p + "negative_control.multichain_4d_destination_scale.pairwise",
      "Negative control: the 4d pairwise check must reject the multi-chain reverse density evaluated with the regions "
      "of x instead of y",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return multichain_4d_pairwise(Fault::kDestinationScale, cx, n); });
  add(p + "negative_control.multichain_4d_without_sigma2.pairwise",
      "Negative control: the 4d pairwise check must reject the multi-chain density stated with sigma_1 for the "
      "continued levels that the proposal draws at sigma_2",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return multichain_4d_pairwise(Fault::kWithoutSigma2, cx, n); });
  add(p + "render.adaptation_target",
      "run_ramlt (ramlt-lens, 4 x 4 grid, Otsu Sec. 8.1 adaptation) on the Cornell box: per region, exact sign test "
      "of the batch acceptance (Eq. 4) against a* (Eq. 5 drives its median to a*; Šidák, alpha 1e-5) and "
      "diminishing steps, |delta lambda| <= 0.25 over the last 10% of the updates (Eq. 6)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return adaptation_target_check({}, cx, n); });
  add(p + "negative_control.constant_gamma.adaptation_target",
      "Negative control: the adaptation-target check must reject a constant step gamma = 1 (gamma_scale -> infinity, "
      "no diminishing adaptation)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o;
        o.adaptation.gamma_scale = 1e12;
        return negate(adaptation_target_check(o, cx, n));
      });
  add(p + "negative_control.fixed_partition.adaptation_target",
      "Negative control: the adaptation-target check must reject the FIXED partition (lambda = 1 never adapted: the "
      "batch acceptance is far from a*)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o;
        o.partition = "fixed";
        return negate(adaptation_target_check(o, cx, n));
      });
  add(p + "render.initial_lambda",
      "run_ramlt (ramlt-lens, 2 x 2 grid) from lambda0 = -10, -5, 0, 1, 5: the final lambda of every region within "
      "5 pooled standard deviations (over 4 seeds at lambda0 = 1) of the seed mean",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return initial_lambda_check({}, cx, n); });
  add(p + "negative_control.frozen_adapter.initial_lambda",
      "Negative control: the initial-lambda check must reject a frozen adapter (gamma_max = 0: lambda stays lambda0)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o;
        o.adaptation.gamma_max = 0.0;
        return negate(initial_lambda_check(o, cx, n));
      });
  add(p + "direction.chi2",
      "Truncated-normal direction kernel (Otsu Sec. 3) against its stated density in (theta, phi), sigma = 0.02, 0.3, "
      "2.5, and the ramlt-lens proposal's realised primary direction at its region's sigma (chi-square, alpha 1e-5, "
      "Šidák)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return direction_chi2(&TruncatedNormalDirection::angle_density, cx, n);
      });
  add(p + "lens.image.cornell",
      "run_ramlt (ramlt-lens, 20 x 20 grid, Otsu Sec. 8.1 defaults; >= 48 chains as Welch samples) against BDPT on "
      "the 8 x 8 Cornell box (Welch t, Stouffer, sum z^2, alpha 1e-5)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return image_check({}, cx, n); });
  add(p + "lens_quadtree.image.cornell",
      "run_ramlt (ramlt-lens, quadtree refined every 65536 mutations above 500 reports; >= 48 chains as Welch "
      "samples) against BDPT on the 8 x 8 Cornell box (alpha 1e-5)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) { return image_check(quadtree(), cx, n); });
  add(p + "multichain.image.caustic_grouped",
      "run_ramlt (ramlt-multichain, 20 x 20 grid) against BDPT on the 16 x 16 caustic scene at depth 10, sums over "
      "pixel groups holding >= 16 expected chain starts each (>= 1024 chains as Welch samples, alpha 1e-5)",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return grouped_image_check(multichain(), cx, n, "caustic.json");
      });
  add(p + "negative_control.lens_destination_scale.pairwise",
      "Negative control: the pairwise check must reject the lens perturbation's reverse density evaluated with the "
      "region of x instead of y",
      CheckKind::kDeterministic,
      [](const CheckContext& cx, const std::string& n) { return lens_pairwise(Fault::kDestinationScale, cx, n); });
  add(p + "negative_control.multichain_destination_scale.pairwise",
      "Negative control: the pairwise check must reject the multi-chain perturbation's reverse density evaluated with "
      "the region of x instead of y",
      CheckKind::kDeterministic, [](const CheckContext& cx, const std::string& n) {
        return multichain_pairwise(Fault::kDestinationScale, cx, n);
      });
  add(p + "negative_control.direction_without_truncation.chi2",
      "Negative control: the direction chi-square must reject the angle density stated without its truncation mass "
      "erf(pi / (sigma sqrt 2))",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        return negate(direction_chi2(&angle_density_without_truncation, cx, n));
      });
  add(p + "negative_control.bidir_missing_geometry.image",
      "Negative control: the image check must reject run_ramlt with a bidirectional density without geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o;
        o.wrap = without_geometry_term;
        return negate(image_check(o, cx, n));
      });
  add(p + "negative_control.bidir_missing_geometry.image_caustic_grouped",
      "Negative control: the grouped caustic image check must reject run_ramlt (multi-chain) with a bidirectional "
      "density without geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o = multichain();
        o.wrap = without_geometry_term;
        return negate(grouped_image_check(o, cx, n, "caustic.json"));
      });
  add(p + "negative_control.bidir_missing_geometry.image_quadtree",
      "Negative control: the quadtree image check must reject run_ramlt with a bidirectional density without "
      "geometry term",
      CheckKind::kStatistical, [](const CheckContext& cx, const std::string& n) {
        RamltOptions o = quadtree();
        o.wrap = without_geometry_term;
        return negate(image_check(o, cx, n));
      });
  return true;
}();

}  // namespace
}  // namespace tb

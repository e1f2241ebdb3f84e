#include "validate/mcmc/registered_mutations.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <fmt/format.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/hash.h"
#include "lib/integrator/path_tracer.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/mcmc/pss/pss_kernel.h"
#include "lib/path/light_sampler.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/pairwise_record.h"
#include "validate/mcmc/path_space/flux_bins.h"
#include "validate/mcmc/path_space/path_projections.h"
#include "validate/mcmc/path_space/scene_cache.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/path_space/reference_density.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"

namespace tb {

namespace {

constexpr int kRes = 16;
constexpr int kMaxDepth = kRegisteredCheckMaxDepth;
constexpr size_t kPerStream = 40;  // uniforms per stream of the dense PSS states (depth 3 reads < 40)

struct Box {
  explicit Box(const std::string& file = "cornell-box.json")
      : world(load_scene_at_resolution(file, kRes, kRes)), lights(std::make_unique<LightSampler>(*world)),
        ctx{world.get(), lights.get()} {}
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
};

// The PSS checks' target: PSSMLT over the path tracer on the box, and Y_ref = the mean of pi over
// 4096 uniform dense states (stream key name + ".y_ref").
struct PssCornell {
  Box box;
  pss::SampleFunction f;
  double y_ref = 0.0;
  PssCornell(const CheckContext& ctx, const std::string& name) {
    using namespace pss;
    RenderSettings rs;
    rs.max_depth = kMaxDepth;
    f = radiance_sample_function(kRes, kRes,
                                 [c = box.ctx, rs](const Vec2& r, Uniforms& u) { return pt_sample(c, rs, r, u); });
    Rng rng = Rng::for_sample(ctx.seed, hash_string(name + ".y_ref"), 0);
    DenseState x(kStreams * kPerStream);
    for (int i = 0; i < 4096; ++i) {
      for (double& v : x) v = rng.uniform();
      y_ref += evaluate_dense(f, 0, x).value / 4096.0;
    }
  }
};

// Folds per-mutation records into one.
struct Summary {
  CheckResult all;
  std::string msg;
  Summary() {
    all.passed = true;
    all.statistic_name = "max relative |F - B| over mutations";
  }
  void add(const std::string& mutation, const CheckResult& r, nlohmann::json* where) {
    all.passed = all.passed && r.passed;
    all.statistic = std::max(all.statistic, r.statistic);
    all.samples += r.samples;
    (*where)[mutation] = {{"passed", r.passed}, {"max_rel", r.statistic}, {"message", r.message}};
    msg += fmt::format("{}{}: {}", msg.empty() ? "" : "; ", mutation, r.passed ? "balanced" : "VIOLATED");
  }
};

}  // namespace

CheckResult pss_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name,
                                              const PssMutationWrap& wrap) {
  using namespace pss;
  const PssCornell target(ctx, name);
  const SampleFunction& f = target.f;
  const double y_ref = target.y_ref;
  const PssSettings defaults;
  Summary s;
  nlohmann::json per = nlohmann::json::object();
  for (const PssMutationInfo& info : pss_mutations()) {
    PssMutationList one = make_pss_mutations({info.name}, defaults.step_settings());
    if (wrap) one[0] = wrap(one[0]);
    const PssKernel kernel(f, 0, one, defaults.sigma, y_ref);
    const auto start = [&kernel](Uniforms& u) {
      DenseState x0(kStreams * kPerStream);
      for (int tries = 0; tries < 64; ++tries) {  // any start sampler is valid; prefer pi(x) > 0
        for (double& v : x0) v = u.next();
        if (kernel.target_density(x0) > 0) break;
      }
      return x0;
    };
    const auto r = mcmc::check_pairwise_balance<PssKernel>(kernel, start, ctx.size(1000, 10000), ctx.seed,
                                                           hash_string(name + "." + info.name));
    s.add(info.name, pairwise_record(r, name + "." + info.name), &per);
  }
  s.all.message = fmt::format("{} registered PSS mutations: {}", pss_mutations().size(), s.msg);
  s.all.details["mutations"] = per;
  s.all.details["y_ref"] = y_ref;
  return s.all;
}

// ---- proposal chi-square of every registered PSS mutation ------------------------------------------

namespace {

using pss::DenseMove;
using pss::DenseState;
using pss::PssKernel;
using pss::PssMutation;

// A displacement y_i - x_i wrapped to [-1/2, 1/2).
double wrapped_displacement(double y, double x) {
  const double d = y - x;
  const double r = d - std::floor(d + 0.5);
  return r < 0.5 ? r : -0.5;
}

// log T(x -> y with y_i replaced by v), on the move of the background pair (x, y): its reads and
// scales are held fixed, so only the stated density's dependence on y_i enters.
double log_t_replaced(const PssMutation& mut, const DenseState& x, DenseState y, size_t i, double v,
                      const DenseMove& background) {
  y[i] = v;
  DenseMove m(x, y);
  m.reads_x = background.reads_x;
  m.reads_y = background.reads_y;
  m.sigma_x = background.sigma_x;
  m.sigma_y = background.sigma_y;
  return mut.log_density(x, y, m);
}

struct CoordinateTest {
  bool factorises = false;
  double max_deviation = 0.0;  // of the log factor over backgrounds (relative to max(1, |log factor|))
  double lo = -0.5, hi = 0.5;  // the histogram's window of displacements
  std::optional<SamplerChi2Result> chi2;
  std::string problem;
  bool rejects(double a) const { return !factorises || !chi2 || !chi2->passed(a); }
  double p() const { return chi2 && factorises ? chi2->p_value() : 0.0; }
};

// The marginal of coordinate i of y ~ T_0(x -> .) (the kernel's single mutation, proposed by the
// renderer's lazy state) against the stated one (see pss_registered_mutations_chi2).
CoordinateTest test_coordinate(const PssKernel& kernel, const DenseState& x, size_t i, int64_t samples, uint64_t seed,
                               uint64_t key) {
  constexpr int kPilot = 512, kBackgrounds = 8, kValues = 16;
  constexpr double kTolerance = 1e-9;
  const PssMutation& mut = kernel.mutation(0);
  CoordinateTest t;
  // Pilot proposals (their own stream): backgrounds and test values of the factorisation check,
  // and the window of the histogram.
  std::vector<DenseState> pilot;
  for (int k = 0; k < kPilot; ++k) {
    Rng r = Rng::for_sample(seed, hash_values(key, 0x9170u), static_cast<uint64_t>(k));
    RngUniforms u(r);
    if (auto y = kernel.propose(0, x, u)) pilot.push_back(std::move(*y));
  }
  if (pilot.size() < static_cast<size_t>(kBackgrounds + kValues)) {
    t.problem = fmt::format("only {} of {} pilot proposals produced", pilot.size(), kPilot);
    return t;
  }
  // Factorisation: log T(x, y[i <- v]) - log T(x, y[i <- v0]) must not depend on the background y
  // (nor on its move), for every test value v.
  const double v0 = pilot[0][i];
  std::vector<double> first(kValues);
  for (int k = 0; k < kBackgrounds; ++k) {
    const DenseMove m = kernel.move(0, x, pilot[static_cast<size_t>(k)]);
    const double l0 = log_t_replaced(mut, x, pilot[static_cast<size_t>(k)], i, v0, m);
    if (!std::isfinite(l0)) {
      t.max_deviation = std::numeric_limits<double>::infinity();
      t.problem = fmt::format("T = 0 at a proposed value of coordinate {} on background {}", i, k);
      return t;
    }
    for (int j = 0; j < kValues; ++j) {
      const double v = pilot[static_cast<size_t>(kBackgrounds + j)][i];
      const double l = log_t_replaced(mut, x, pilot[static_cast<size_t>(k)], i, v, m) - l0;
      if (k == 0) {
        first[static_cast<size_t>(j)] = l;
        continue;
      }
      const double f = first[static_cast<size_t>(j)];
      const double dev = (l == f) ? 0.0 : std::abs(l - f) / std::max(1.0, std::abs(f));
      t.max_deviation = std::max(t.max_deviation, std::isnan(dev) ? std::numeric_limits<double>::infinity() : dev);
    }
  }
  t.factorises = t.max_deviation <= kTolerance;
  if (!t.factorises) {
    t.problem = fmt::format("the stated T does not factorise in coordinate {}: its log factor varies by {:.3g} over "
                            "backgrounds; no 1D marginal follows from log_density",
                            i, t.max_deviation);
    return t;
  }
  // The window: the pilot's range of displacements widened by its span on each side (a Gaussian
  // step: about +-9 sigma), the whole circle when that covers most of it. Displacements outside
  // are counted as failed samples, against the stated mass outside.
  double dmin = 0.5, dmax = -0.5;
  for (const DenseState& y : pilot) {
    const double d = wrapped_displacement(y[i], x[i]);
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  const double span = std::max(dmax - dmin, 1e-9);
  t.lo = std::max(-0.5, dmin - span);
  t.hi = std::min(0.5, dmax + span);
  if (t.hi - t.lo > 0.8) t.lo = -0.5, t.hi = 0.5;
  // The stated marginal: the 1D factor on background 0, normalised over the circle by adaptive
  // Gauss-Kronrod quadrature (101 window cells and the two pieces outside).
  const DenseMove m0 = kernel.move(0, x, pilot[0]);
  const double l_ref = log_t_replaced(mut, x, pilot[0], i, v0, m0);
  const auto factor = [&](double d) {
    const double l = log_t_replaced(mut, x, pilot[0], i, pss::wrap01(x[i] + d), m0) - l_ref;
    return std::isfinite(l) ? std::exp(l) : 0.0;
  };
  // Outside the window (no pilot proposal there), 64 fixed 15-point rules per piece: a stated peak
  // narrower than they resolve would make z too small and the expected counts too large, so it is
  // rejected, never hidden.
  using GK = boost::math::quadrature::gauss_kronrod<double, 15>;
  constexpr int kCells = 101, kOutside = 64;
  double z = 0.0;
  for (int c = 0; c < kCells; ++c) {
    const double a = t.lo + (t.hi - t.lo) * c / kCells, b = t.lo + (t.hi - t.lo) * (c + 1) / kCells;
    z += GK::integrate(factor, a, b, 6, 1e-9);
  }
  for (const auto& [a, b] : {std::pair{-0.5, t.lo}, std::pair{t.hi, 0.5}})
    for (int c = 0; c < kOutside && b > a; ++c)
      z += GK::integrate(factor, a + (b - a) * c / kOutside, a + (b - a) * (c + 1) / kOutside, 0);
  if (!(z > 0.0) || !std::isfinite(z)) {
    t.problem = fmt::format("the stated factor of coordinate {} integrates to {}", i, z);
    t.factorises = false;
    return t;
  }
  const double lo = t.lo, hi = t.hi;
  const auto sample = [&](Uniforms& u) -> std::optional<double> {
    const auto y = kernel.propose(0, x, u);
    if (!y) return std::nullopt;
    const double d = wrapped_displacement((*y)[i], x[i]);
    if (d < lo || d >= hi) return std::nullopt;  // outside the window: the failure cell
    return d;
  };
  const auto pdf = [&](double d) { return factor(d) / z; };
  SamplerChi2Options o;
  o.samples = samples;
  o.seed = seed;
  o.key = key;
  t.chi2 = chi2_test(Chi2Domain::interval(lo, hi, kCells), sample, pdf, o);
  return t;
}

}  // namespace

CheckResult pss_registered_mutations_chi2(const CheckContext& ctx, const std::string& name,
                                          const PssMutationWrap& wrap) {
  using namespace pss;
  constexpr double kFamilyAlpha = 1e-3;
  // Coordinate 0: the camera stream's first uniform (the raster), read by every state; coordinate
  // kLightStream: the light stream's first uniform, which the path tracer never reads (it moves as
  // an unread coordinate does, pss_kernel.h).
  const std::vector<size_t> coordinates = {0, static_cast<size_t>(kLightStream)};
  const PssCornell target(ctx, name);
  const PssSettings defaults;
  // States: the dimmest, the median and the brightest of the first 64 uniform states with pi > 0.
  std::vector<std::pair<double, DenseState>> lit;
  {
    Rng rng = Rng::for_sample(ctx.seed, hash_string(name + ".states"), 0);
    DenseState x(kStreams * kPerStream);
    for (int tries = 0; tries < 100000 && lit.size() < 64; ++tries) {
      for (double& v : x) v = rng.uniform();
      const double pi = evaluate_dense(target.f, 0, x).value;
      if (pi > 0.0) lit.emplace_back(pi, x);
    }
    std::sort(lit.begin(), lit.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  std::vector<std::pair<std::string, size_t>> states;
  if (!lit.empty()) states = {{"dim", 0}, {"median", lit.size() / 2}, {"bright", lit.size() - 1}};
  const auto& infos = pss_mutations();
  const int64_t tests = static_cast<int64_t>(infos.size() * states.size() * coordinates.size());
  const double a = stats::sidak_alpha(kFamilyAlpha, std::max<int64_t>(1, tests));
  const int64_t samples = ctx.size(40000, 200000);

  CheckResult all;
  all.statistic_name = "Šidák-adjusted min p over (mutation, state, coordinate)";
  all.alpha = kFamilyAlpha;
  bool all_factorise = true, every_rejected = !infos.empty();
  double p_min = 1.0;
  std::string msg;
  nlohmann::json per = nlohmann::json::object();
  for (const PssMutationInfo& info : infos) {
    PssMutationList one = make_pss_mutations({info.name}, defaults.step_settings());
    if (wrap) one[0] = wrap(one[0]);
    const PssKernel kernel(target.f, 0, one, defaults.sigma, target.y_ref);
    nlohmann::json rows = nlohmann::json::array();
    bool rejected = false, factorises = true;
    double mp = 1.0;
    std::string problem;
    for (size_t sidx = 0; sidx < states.size(); ++sidx) {
      const auto& [pi, x] = lit[states[sidx].second];
      const double scale = kernel.mutation(0).scale(pi, target.y_ref);
      for (size_t i : coordinates) {
        const CoordinateTest t = test_coordinate(kernel, x, i, samples, ctx.seed,
                                                 hash_values(hash_string(name + "." + info.name), sidx, i));
        factorises = factorises && t.factorises;
        rejected = rejected || (t.chi2 && !t.chi2->passed(a));
        mp = std::min(mp, t.p());
        if (!t.problem.empty() && problem.empty()) problem = t.problem;
        nlohmann::json row = {{"state", states[sidx].first},
                              {"pi", pi},
                              {"scale", scale},
                              {"coordinate", i},
                              {"factorises", t.factorises},
                              {"max_log_factor_deviation", t.max_deviation},
                              {"window", {t.lo, t.hi}}};
        if (!t.problem.empty()) row["problem"] = t.problem;
        if (t.chi2) {
          row["p"] = t.chi2->p_value();
          row["chi2"] = t.chi2->gof.statistic;
          row["dof"] = t.chi2->gof.dof;
          row["samples"] = t.chi2->samples;
          row["failed"] = t.chi2->failed;
          row["window_mass"] = t.chi2->pdf_integral;
          row["message"] = t.chi2->message();
          all.samples += t.chi2->samples;
        }
        rows.push_back(row);
      }
    }
    all_factorise = all_factorise && factorises;
    every_rejected = every_rejected && rejected;
    p_min = std::min(p_min, mp);
    per[info.name] = {{"passed", factorises && !(mp < a)}, {"rejected", rejected}, {"factorises", factorises},
                      {"min_p", mp}, {"tests", rows}};
    msg += fmt::format("{}{}: {}", msg.empty() ? "" : "; ", info.name,
                       !factorises ? "DOES NOT FACTORISE (" + problem + ")"
                                   : fmt::format("min p = {:.3g}{}", mp, rejected ? " REJECTED" : ""));
  }
  all.statistic = stats::sidak_adjust(p_min, std::max<int64_t>(1, tests));
  all.p_value = all.statistic;
  all.passed = states.size() == 3 && all_factorise && !(p_min < a);
  all.message = fmt::format("{} registered PSS mutations x {} states x {} coordinates, {} samples each: Šidák p = {:.3g} "
                            "(family alpha {:g}, per test {:.3g}){}: {}",
                            infos.size(), states.size(), coordinates.size(), samples, all.statistic, kFamilyAlpha, a,
                            states.size() == 3 ? "" : " [no state with pi > 0 found]", msg);
  nlohmann::json st = nlohmann::json::array();
  for (const auto& [label, idx] : states) st.push_back({{"label", label}, {"pi", lit[idx].first}});
  all.details["mutations"] = per;
  all.details["states"] = st;
  all.details["y_ref"] = target.y_ref;
  all.details["alpha_family"] = kFamilyAlpha;
  all.details["alpha_per_test"] = a;
  all.details["tests"] = tests;
  all.details["samples_per_test"] = samples;
  all.details["every_mutation_rejected"] = every_rejected;
  return all;
}

CheckResult path_registered_mutations_pairwise(const CheckContext& ctx, const std::string& name,
                                               const PathMutationWrap& wrap) {
  using namespace path_space;
  // The Cornell box first; a mutation with too few pairs carrying flux there (one that acts on
  // specular chains only) is checked on the caustic scene, from start paths it applies to.
  const std::vector<std::string> scenes = {"cornell-box.json", "caustic.json"};
  std::vector<std::unique_ptr<Box>> boxes;
  for (const auto& file : scenes) boxes.push_back(std::make_unique<Box>(file));
  PathMutationSettings ms;
  ms.max_segments = kMaxDepth + 1;
  Summary s;
  nlohmann::json per = nlohmann::json::object();
  const size_t count = path_mutations().size();
  for (size_t i = 0; i < count; ++i) {
    CheckResult last;
    for (size_t b = 0; b < boxes.size(); ++b) {
      const PathContext& pc = boxes[b]->ctx;
      PathMutationList list = make_all_path_mutations(pc, ms);
      // The reference is that of the registered mutation; a wrapper (negative control) is checked
      // against it, so a density it misstates is seen.
      const auto ref_one = reference_density_of(*list[i], pc);
      const std::shared_ptr<const PathMutation> keep = list[i];
      if (wrap) list[i] = wrap(list[i], pc);
      const PathMutation& m = *list[i];
      const auto start = [&pc, &m](Uniforms& u) {
        MltPath any;
        for (int a = 0; a < 1024; ++a)
          if (auto p = sample_bdpt_path(pc, u, kMaxDepth)) {
            if (m.weight(*p) > 0.0) return *p;
            any = *p;
          }
        return any;
      };
      const auto kernel = mcmc::MetropolisHastings(PathTarget{&pc}, mcmc::SingleProposal(MutationProposal{&m, nullptr}));
      using K = decltype(kernel);
      const auto ref = [&ref_one](int, const MltPath& x, const MltPath& y) { return ref_one(x, y); };
      // Redraws of proposals without flux: more on the specular scene, where many end on a changed chain.
      const WithReferenceDensity<K, decltype(ref)> k(kernel, ref, b == 0 ? 8 : 64);
      const auto r = mcmc::check_pairwise_balance<WithReferenceDensity<K, decltype(ref)>>(
          k, start, ctx.size(400, 10000), ctx.seed, hash_string(name + "." + m.name()));
      last = pairwise_record(r, name + "." + m.name());
      last.message = scenes[b] + ": " + last.message;
      if (2 * r.live >= r.pairs) break;  // enough pairs with flux on this scene
    }
    s.add(path_mutations()[i].name, last, &per);
  }
  s.all.message = fmt::format("{} registered path mutations: {}", count, s.msg);
  s.all.details["mutations"] = per;
  return s.all;
}

CheckResult path_registered_mutations_flux_bins(const CheckContext& ctx, const std::string& name,
                                                const PathMutationWrap& wrap) {
  using namespace path_space;
  constexpr double kAlpha = 1e-5;
  constexpr int64_t kMinCrossings = 20;
  // The Cornell box; then a glossy scene and the scenes with specular chains, for mutations that
  // act on those only.
  const std::vector<std::string> scenes = {"cornell-box.json", "glossy.json", "caustic.json", "dg-mirror-chain.json",
                                           "dg-glass.json"};
  std::vector<std::unique_ptr<Box>> boxes(scenes.size());  // loaded when first needed
  PathMutationSettings ms;
  ms.max_segments = kMaxDepth + 1;
  const size_t count = path_mutations().size();
  CheckResult all;
  all.statistic_name = "Šidák-adjusted min p over mutations (each: Šidák over its bin pairs)";
  all.alpha = kAlpha;
  nlohmann::json per = nlohmann::json::object();
  std::string msg;
  double p_min = 1.0;
  bool every_tested = true;
  for (size_t i = 0; i < count; ++i) {
    FluxBinTest t;
    std::string where;
    int64_t crossings = 0;
    for (size_t b = 0; b < boxes.size() && t.tested == 0; ++b) {
      if (!boxes[b]) boxes[b] = std::make_unique<Box>(scenes[b]);
      const PathContext& pc = boxes[b]->ctx;
      PathMutationList list = make_all_path_mutations(pc, ms);
      std::shared_ptr<const PathMutation> m = list[i];
      if (wrap) m = wrap(m, pc);
      FluxBinOptions o;
      o.chains = ctx.size(2048, 16384);
      o.burn_in = 8;
      o.steps = 100;
      o.block = 8;
      o.max_depth = kMaxDepth;
      o.seed = ctx.seed;
      o.key = hash_string(name + "." + m->name() + "." + scenes[b]);
      const FluxBinCounts f = flux_bins(mcmc::MetropolisHastings(PathTarget{&pc}, PathMixture({m})), pc, o);
      t = flux_bin_test(f, kMinCrossings);
      where = scenes[b];
      crossings = f.crossings;
      all.samples += f.crossings;
    }
    const std::string& mn = path_mutations()[i].name;
    every_tested = every_tested && t.tested > 0;
    p_min = std::min(p_min, t.p_family);
    per[mn] = {{"scene", where},        {"pairs_tested", t.tested}, {"crossings", crossings},
               {"p_family", t.p_family}, {"worst_pair", {t.worst.first, t.worst.second}},
               {"worst_n_ab", t.worst_ab}, {"worst_n_ba", t.worst_ba}};
    msg += fmt::format("{}{} ({}, {} pairs): p = {:.3g}", msg.empty() ? "" : "; ", mn, where, t.tested, t.p_family);
  }
  all.statistic = stats::sidak_adjust(p_min, static_cast<int64_t>(count));
  all.p_value = all.statistic;
  all.passed = every_tested && !(all.statistic < kAlpha);
  all.message = fmt::format("{} registered path mutations, Šidák p = {:.3g}{}: {}", count, all.statistic,
                            every_tested ? "" : " [a mutation had no bin pair tested]", msg);
  all.details["mutations"] = per;
  return all;
}

CheckResult path_registered_mutations_chi2(const CheckContext& ctx, const std::string& name,
                                           const PathMutationWrap& wrap) {
  using namespace path_space;
  constexpr double kFamilyAlpha = 1e-5;
  constexpr int kRes = 16;
  PathMutationSettings ms;
  ms.max_segments = 5;  // the projections' test paths: max depth 4
  struct Test {
    std::string mutation, scene, label;
    SamplerChi2Result r;
  };
  std::vector<Test> tests;
  struct Entry {
    std::string status, note;
  };
  std::vector<std::pair<std::string, Entry>> entries;
  const auto& infos = path_mutations();
  for (size_t i = 0; i < infos.size(); ++i) {
    const std::string& mn = infos[i].name;
    const PathProjectionInfo* proj = find_path_projection(mn);
    if (!proj) {
      entries.push_back({mn, {"no projection", "NO CHI-SQUARE PROJECTION DECLARED (register_path_projection, or a "
                                               "no_projection_reason)"}});
      continue;
    }
    if (!proj->no_projection_reason.empty()) {
      entries.push_back({mn, {"exempt", "not tested: " + proj->no_projection_reason}});
      continue;
    }
    size_t before = tests.size();
    std::string error;
    try {
      for (const std::string& file : proj->scenes) {
        const LoadedScene& sc = cached_scene(file, kRes);
        const PathMutationList list = make_all_path_mutations(sc.ctx, ms);
        const std::shared_ptr<const PathMutation> reg = list[i];
        const std::shared_ptr<const PathMutation> checked = wrap ? wrap(reg, sc.ctx) : reg;
        const uint64_t seed = hash_values(ctx.seed, hash_string(mn + "." + file));
        const PathProjectionInput in{sc.ctx, *reg, *checked, seed};
        int configs = 0;
        for (const MltPath& x : proj->paths(sc.ctx, *reg, seed)) {
          for (const auto& p : proj->make(in, x)) {
            if (proj->configs_per_scene > 0 && configs >= proj->configs_per_scene) break;
            SamplerChi2Options o;
            o.samples = ctx.size(proj->quick_samples, proj->full_samples);
            o.seed = ctx.seed;
            o.key = hash_values(hash_string(name + "." + mn + "." + file), static_cast<uint64_t>(configs));
            o.quadrature_max_depth = proj->quadrature_max_depth;
            o.monte_carlo_expected = proj->monte_carlo_expected;
            tests.push_back({mn, file, p->label(),
                             chi2_test(Chi2Domain::rectangle(p->chart_lo(), p->chart_hi(), proj->cells_x, proj->cells_y),
                                       [&p](Uniforms& u) { return p->sample(u); },
                                       [&p](const Vec2& q) { return p->pdf(q); }, o)});
            ++configs;
          }
          if (proj->configs_per_scene > 0 && configs >= proj->configs_per_scene) break;
        }
      }
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (!error.empty())
      entries.push_back({mn, {"error", "ERROR: " + error}});
    else if (tests.size() == before)
      entries.push_back({mn, {"nothing tested", "NOTHING TESTED: no configuration on its scenes"}});
    else
      entries.push_back({mn, {"tested", proj->coordinate}});
  }
  const int64_t m = std::max<int64_t>(1, static_cast<int64_t>(tests.size()));
  const double a = stats::sidak_alpha(kFamilyAlpha, m);
  CheckResult all;
  all.statistic_name = "Šidák-adjusted min p over (mutation, configuration)";
  all.alpha = kFamilyAlpha;
  bool ok = true, every_rejected = true, any_tested = false, every_covered = true;
  double p_min = 1.0;
  std::string msg;
  nlohmann::json per = nlohmann::json::object();
  for (const auto& [mn, e] : entries) {
    nlohmann::json rows = nlohmann::json::array();
    double mp = 1.0;
    bool rejected = false;
    for (const Test& t : tests) {
      if (t.mutation != mn) continue;
      const bool rej = !t.r.passed(a);
      rejected = rejected || rej;
      mp = std::min(mp, t.r.p_value());
      all.samples += t.r.samples;
      nlohmann::json row = t.r.details();
      row["scene"] = t.scene;
      row["configuration"] = t.label;
      row["p"] = t.r.p_value();
      row["rejected"] = rej;
      row["message"] = t.r.message();
      rows.push_back(row);
    }
    const bool tested = e.status == "tested";
    const bool passed = e.status == "exempt" || (tested && !rejected);
    ok = ok && passed;
    every_covered = every_covered && (tested || e.status == "exempt");
    if (tested) {
      any_tested = true;
      every_rejected = every_rejected && rejected;
      p_min = std::min(p_min, mp);
    }
    per[mn] = {{"status", e.status}, {"passed", passed}, {"rejected", rejected}, {"min_p", mp},
               {"note", e.note}, {"tests", rows}};
    msg += fmt::format("{}{}: {}", msg.empty() ? "" : "; ", mn,
                       tested ? fmt::format("{} tests, min p = {:.3g}{}", rows.size(), mp, rejected ? " REJECTED" : "")
                              : e.note);
  }
  all.statistic = stats::sidak_adjust(p_min, m);
  all.p_value = all.statistic;
  all.passed = ok && any_tested;
  all.message = fmt::format("{} registered path mutations, {} tests: Šidák p = {:.3g} (family alpha {:g}, per test "
                            "{:.3g}): {}",
                            infos.size(), tests.size(), all.statistic, kFamilyAlpha, a, msg);
  all.details["mutations"] = per;
  all.details["alpha_family"] = kFamilyAlpha;
  all.details["alpha_per_test"] = a;
  all.details["tests"] = static_cast<int64_t>(tests.size());
  all.details["every_tested_rejected"] = any_tested && every_rejected;
  // Every registered mutation tested (or exempt with its reason): a control that rejects only
  // the mutations it reached must not count as caught when one was not reached.
  all.details["every_registered_covered"] = every_covered;
  return all;
}

}  // namespace tb

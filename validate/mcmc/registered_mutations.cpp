#include "validate/mcmc/registered_mutations.h"

#include <algorithm>
#include <memory>
#include <vector>

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
#include "validate/mcmc/path_space/reference_density.h"
#include "validate/render/render_compare.h"

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
  const Box box;
  RenderSettings rs;
  rs.max_depth = kMaxDepth;
  const SampleFunction f = radiance_sample_function(
      kRes, kRes, [c = box.ctx, rs](const Vec2& r, Uniforms& u) { return pt_sample(c, rs, r, u); });
  Rng rng = Rng::for_sample(ctx.seed, hash_string(name + ".y_ref"), 0);
  DenseState x(kStreams * kPerStream);
  double y_ref = 0.0;
  for (int i = 0; i < 4096; ++i) {
    for (double& v : x) v = rng.uniform();
    y_ref += evaluate_dense(f, 0, x).value / 4096.0;
  }
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

}  // namespace tb

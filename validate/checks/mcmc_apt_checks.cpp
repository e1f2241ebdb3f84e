// Checks of the APT small step (Zirr & Dachsbacher 2020, Sec. 7.1, Listing 1; lib/mcmc/apt_small_step.h)
// at fixed path length, through the generic Metropolis-Hastings kernel (estimators/mcmc/
// metropolis_hastings.h) over the step as a single proposal:
//  * mcmc.apt.<scene>.pairwise: pairwise detailed balance to 1e-9 (validate/mcmc/pairwise_balance.h)
//    on seeded pairs, x a uniform state with f(x) > 0 where one is found within kStartTries draws;
//  * mcmc.apt.negative_control.symmetric_assumption.pairwise: the same kernel with T(x -> y) used
//    for both directions (ForwardDensityBothWays, validate/mcmc/apt_broken.h) must violate balance;
//  * mcmc.apt.cornell.chi2: the 1D marginals of the film coordinate, of the first bounce's first
//    direction uniform and of its lobe uniform (d = y_i - x_i wrapped, in cells of atan(d / sigma))
//    at three states against the stated density's factor for that coordinate (T is their
//    product), 401 cells, alpha 1e-5 Šidák over the nine tests; negative control: the factor stated with sigma 5 % too wide (MisstatedAptFactor).
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "estimators/mcmc/metropolis_hastings.h"
#include "estimators/mcmc/proposal_mixture.h"
#include "lib/core/hash.h"
#include "lib/core/math.h"
#include "lib/core/rng.h"
#include "lib/mcmc/apt_small_step.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/mcmc/apt_broken.h"
#include "validate/mcmc/pairwise_balance.h"
#include "validate/mcmc/pairwise_record.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"
#include "validate/stats/tests.h"

namespace tb {
namespace {

using mcmc::AptScales;
using mcmc::AptSmallStep;
using mcmc::AptState;
using mcmc::AptTarget;
constexpr double kChi2Alpha = 1e-5;
constexpr int kRes = 16;
// Uniform draws per start state: at k = 3 roughly 1 in 1400 uniform states of the Cornell box has
// f > 0 (17 % of starts found one within 256 draws), on the glossy scene fewer.
constexpr int kStartTries = 16384;

using AptKernel = mcmc::MetropolisHastings<AptTarget, mcmc::SingleProposal<AptSmallStep>>;

AptState start_state(const AptTarget& t, Uniforms& u) {
  AptState x(t.dimension());
  for (int tries = 0; tries < kStartTries; ++tries) {  // any start sampler is valid; prefer f(x) > 0
    for (double& v : x) v = u.next();
    if (t.density(x) > 0.0) break;
  }
  return x;
}

template <class K>
CheckResult run_pairwise(const K& kernel, const AptTarget& target, const CheckContext& ctx, const std::string& name) {
  const auto start = [&target](Uniforms& u) { return start_state(target, u); };
  const auto r = mcmc::check_pairwise_balance<K>(kernel, start, ctx.size(2000, 20000), ctx.seed, hash_string(name));
  CheckResult res = pairwise_record(r, name);
  // How often the KKT loop removed a group (Listing 1 lines 22-26), how the scales spread and the
  // mean acceptance of one proposal (the kernel's own, broken or not), over the same start states.
  int64_t removed = 0, states = 0;
  double smin = 1.0, smax = 0.0, acceptance = 0.0;
  for (int64_t i = 0; i < std::min<int64_t>(r.pairs, 500); ++i) {
    Rng rng = Rng::for_sample(ctx.seed, hash_string(name), static_cast<uint64_t>(i));
    RngUniforms u(rng);
    const AptState x = start_state(target, u);
    if (!(target.density(x) > 0.0)) continue;
    const AptScales s = target.scales(x);
    ++states;
    if (const auto m = kernel.sample_move(x, u)) acceptance += kernel.acceptance(x, *m);
    removed += s.kkt.rounds > 1 ? 1 : 0;
    for (double v : s.sigma) {
      smin = std::min(smin, v);
      smax = std::max(smax, v);
    }
  }
  res.details["states_with_f"] = states;
  res.details["states_with_kkt_removal"] = removed;
  res.details["sigma_min"] = smin;
  res.details["sigma_max"] = smax;
  res.details["mean_acceptance"] = states > 0 ? acceptance / static_cast<double>(states) : 0.0;
  res.message += fmt::format("; over {} start states with f > 0: sigma in [{:.3g}, {:.3g}], KKT removed a group in {}, "
                             "mean acceptance of one proposal {:.3f}",
                             states, smin, smax, removed, states > 0 ? acceptance / static_cast<double>(states) : 0.0);
  return res;
}

CheckResult apt_pairwise(const CheckContext& ctx, const std::string& scene, int res, int k, bool broken,
                         const std::string& name) {
  const auto world = load_scene_at_resolution(scene, res, res);
  const AptTarget target(*world, k);
  const AptKernel kernel(target, mcmc::SingleProposal<AptSmallStep>(AptSmallStep(target)));
  if (!broken) return run_pairwise(kernel, target, ctx, name);
  CheckResult r = run_pairwise(mcmc::ForwardDensityBothWays<AptKernel>(kernel), target, ctx, name);
  r.passed = r.details.value("violations", int64_t{0}) > 0;
  r.message = (r.passed ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ") + r.message;
  return r;
}

// The factor of coordinate i stated by the step, or a misstated one.
template <class Factor>
CheckResult apt_chi2(const CheckContext& ctx, const Factor& factor, bool broken, const std::string& name) {
  const auto world = load_scene_at_resolution("cornell-box.json", kRes, kRes);
  const AptTarget target(*world, 3);
  const AptSmallStep step(target);
  Rng rng = Rng::for_sample(ctx.seed, hash_string(name + ".states"), 0);
  RngUniforms su(rng);
  std::vector<AptState> xs;
  for (int tries = 0; tries < 100 && xs.size() < 3; ++tries) {
    AptState x = start_state(target, su);
    if (target.density(x) > 0.0) xs.push_back(std::move(x));
  }
  const size_t coords[3] = {0, 2, 4};
  const int tests = 3 * static_cast<int>(xs.size());
  const double a = stats::sidak_alpha(kChi2Alpha, std::max(1, tests));
  CheckResult res;
  res.statistic_name = "smallest p";
  res.statistic = 1.0;
  res.alpha = kChi2Alpha;
  bool any_reject = false;
  std::string msg;
  for (size_t c = 0; c < xs.size(); ++c) {
    const AptState& x0 = xs[c];
    const AptScales sx = target.scales(x0);
    for (size_t i : coords) {
      // Cells in v = 1/2 + atan(d / c) / pi, d = y_i - x_i wrapped to [-1/2, 1/2], c = the step's
      // own sigma of the coordinate's group (a fixed bijection for the test; the stated density is
      // transformed with it): the Gaussian's mass spreads over most of the 401 cells whatever sigma.
      const double c_map = sx.sigma[static_cast<size_t>(AptTarget::group(i))];
      const auto sample = [&](Uniforms& u) -> std::optional<double> {
        const auto y = step.propose(x0, u);
        if (!y) return std::nullopt;
        double d = (*y)[i] - x0[i];
        d -= std::round(d);  // [-1/2, 1/2]
        return std::clamp(0.5 + std::atan(d / c_map) / kPi, 0.0, std::nextafter(1.0, 0.0));
      };
      const auto pdf = [&](double v) {
        const double d = c_map * std::tan(kPi * (v - 0.5));
        if (!(std::abs(d) <= 0.5)) return 0.0;
        return factor(sx, i, d) * c_map * kPi * (1.0 + (d / c_map) * (d / c_map));
      };
      SamplerChi2Options o;
      o.samples = ctx.size(100000, 400000);
      o.seed = ctx.seed;
      o.key = hash_string(fmt::format("{}.{}.{}", name, c, i));
      const auto r = chi2_test(Chi2Domain::interval(0.0, 1.0, 401), sample, pdf, o);
      const bool rej = !r.passed(a);
      any_reject = any_reject || rej;
      res.statistic = std::min(res.statistic, r.gof.p_value);
      res.samples += r.samples;
      msg += fmt::format("{}state {} coord {} (sigma {:.4g}): chi2 {:.1f} / {} dof, p {:.3g}", msg.empty() ? "" : "; ", c,
                         i, sx.sigma[static_cast<size_t>(AptTarget::group(i))], r.gof.statistic, r.gof.dof,
                         r.gof.p_value);
    }
  }
  res.passed = xs.size() == 3 && (broken ? any_reject : !any_reject);
  res.message = (broken ? (any_reject ? "broken variant rejected as required: " : "BROKEN VARIANT NOT DETECTED: ")
                        : std::string()) +
                fmt::format("Šidák alpha {:.3g} over {} tests; ", a, tests) + msg;
  return res;
}

const bool registered = [] {
  Registry::global().add(Check{
      .name = "mcmc.apt.cornell.pairwise",
      .description = "APT small step (Zirr 2020 Listing 1, k = 3 vertices, 256x256 Cornell box) through Metropolis-"
                     "Hastings: pairwise detailed balance to 1e-9 on seeded pairs",
      .kind = CheckKind::kDeterministic,
      .run = [](const CheckContext& ctx) {
        return apt_pairwise(ctx, "cornell-box.json", 256, 3, false, "mcmc.apt.cornell.pairwise");
      }});
  Registry::global().add(Check{
      .name = "mcmc.apt.glossy.pairwise",
      .description = "APT small step, k = 2, 256x256 glossy scene: pairwise detailed balance to 1e-9",
      .kind = CheckKind::kDeterministic,
      .run = [](const CheckContext& ctx) {
        return apt_pairwise(ctx, "glossy.json", 256, 2, false, "mcmc.apt.glossy.pairwise");
      }});
  Registry::global().add(Check{
      .name = "mcmc.apt.curved_mirrors.pairwise",
      .description = "APT small step, k = 2, 256x256 dg-curved-mirrors (Dirac vertices: groups inactive from the "
                     "start, sigma = (2 pi)^-1/2): pairwise detailed balance to 1e-9",
      .kind = CheckKind::kDeterministic,
      .run = [](const CheckContext& ctx) {
        return apt_pairwise(ctx, "dg-curved-mirrors.json", 256, 2, false, "mcmc.apt.curved_mirrors.pairwise");
      }});
  Registry::global().add(Check{
      .name = "mcmc.apt.negative_control.symmetric_assumption.pairwise",
      .description = "APT small step accepted with T(x -> y) for both directions (symmetric assumption): the pairwise "
                     "balance check must find violations",
      .kind = CheckKind::kDeterministic,
      .run = [](const CheckContext& ctx) {
        return apt_pairwise(ctx, "cornell-box.json", 256, 3, true,
                            "mcmc.apt.negative_control.symmetric_assumption.pairwise");
      }});
  Registry::global().add(Check{
      .name = "mcmc.apt.cornell.chi2",
      .description = "APT small step proposal chi-square: 1D marginals of coordinates 0, 2 and 4 at three states against "
                     "the stated density's factor, 401 cells, alpha 1e-5 Šidák",
      .kind = CheckKind::kStatistical,
      .run = [](const CheckContext& ctx) {
        return apt_chi2(ctx, [](const AptScales& s, size_t i, double d) { return AptSmallStep::factor(s, i, d); },
                        false, "mcmc.apt.cornell.chi2");
      }});
  Registry::global().add(Check{
      .name = "mcmc.apt.negative_control.misstated_sigma.chi2",
      .description = "the APT chi-square must reject the step's factor stated with sigma 5 % too wide",
      .kind = CheckKind::kStatistical,
      .run = [](const CheckContext& ctx) {
        return apt_chi2(ctx, mcmc::MisstatedAptFactor{}, true, "mcmc.apt.negative_control.misstated_sigma.chi2");
      }});
  return true;
}();

}  // namespace
}  // namespace tb

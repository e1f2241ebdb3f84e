// Image checks of the apt integrator (lib/mcmc/apt_integrator.h; Zirr & Dachsbacher 2020, Sec. 7):
//  * render.apt.<scene>.unbiased (cornell, glossy): apt against a longer path-tracer reference,
//    Welch's t-test per pixel and channel over independent passes (each pass its own bootstrap and
//    chains: a Welch sample), compare_channels at alpha = 0.01 (Šidák inside, plus Stouffer and
//    sum z^2), over the pixels the chains visit at least 64 times per pass in expectation
//    (pss::expected_visits of the reference; the others have far-from-normal Welch samples), as
//    render.pssmlt.cornell.unbiased does (mcmc_pss_checks.cpp);
//  * render.apt.negative_control.no_rejected_splat (cornell, glossy): expected-value splatting
//    without the (1 - a) splat of the current state (validate/mcmc/apt_broken.h) must be rejected;
//  * render.apt.negative_control.bootstrap_last_candidate: the normalisation b (and the chains'
//    starts) from the full-length candidate of each bootstrap draw only, not the sum over its
//    prefixes, must be rejected.
// Fixed seeds: the run seed hashed with the check's name.
#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/integrator/path_tracer.h"
#include "lib/mcmc/apt_integrator.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "validate/mcmc/apt_broken.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

constexpr double kAlpha = 0.01;    // per image check (Šidák inside compare_channels)
constexpr int kMaxDepth = 3;       // paths of up to 4 segments
// Expected mutations per pixel and pass to enter the t-test: twice the PSS checks' 32, because apt's
// chains are stickier (large-step acceptance about 0.012 on the Cornell box, small step 0.17), so
// a pixel's Welch samples are more skewed at the same number of visits.
constexpr double kMinVisits = 64;

enum class AptFault { kNone, kNoRejectedSplat, kBootstrapLastCandidate };

struct Size {
  int res;
  int64_t passes, ref_spp_pass, spp_pass;
};

Size size_of(const CheckContext& ctx, const std::string& scene) {
  const bool cornell = scene == "cornell-box.json";
  Size s = cornell ? (ctx.full ? Size{24, 64, 1024, 128} : Size{16, 32, 512, 192})
                   : (ctx.full ? Size{16, 64, 2048, 256} : Size{8, 32, 1024, 256});
  s.ref_spp_pass = std::max<int64_t>(1, static_cast<int64_t>(double(s.ref_spp_pass) * ctx.sample_scale));
  s.spp_pass = std::max<int64_t>(1, static_cast<int64_t>(double(s.spp_pass) * ctx.sample_scale));
  return s;
}

// The path-tracer reference, rendered once per (scene, size, seed) and shared by check and controls.
std::shared_ptr<const Film> pt_reference(const World& world, const std::string& scene, const Size& sz, uint64_t seed) {
  static std::mutex mu;
  static std::map<std::tuple<std::string, int, int64_t, int64_t, uint64_t>, std::shared_ptr<const Film>> cache;
  const auto key = std::make_tuple(scene, sz.res, sz.passes, sz.ref_spp_pass, seed);
  std::lock_guard<std::mutex> lock(mu);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  RenderSettings st;
  st.passes = sz.passes;
  st.spp = sz.passes * sz.ref_spp_pass;
  st.max_depth = kMaxDepth;
  st.seed = hash_values(seed, hash_string("render.apt.pt_reference"), hash_string(scene));
  auto film = std::make_shared<Film>(sz.res, sz.res);
  render_pt(world, st, *film);
  cache[key] = film;
  return film;
}

CheckResult run_apt_image(const CheckContext& ctx, const std::string& scene, AptFault fault, const std::string& name) {
  Size sz = size_of(ctx, scene);
  if (fault != AptFault::kNone) sz.spp_pass = std::max<int64_t>(8, sz.spp_pass / 4);  // caught by far
  const auto world = load_scene_at_resolution(scene, sz.res, sz.res);
  const auto ref = pt_reference(*world, scene, sz, ctx.seed);
  RenderSettings st;
  st.passes = sz.passes;
  st.spp = sz.passes * sz.spp_pass;
  st.max_depth = kMaxDepth;
  st.seed = hash_values(ctx.seed, hash_string(name));
  st.progress = [&ctx](double p) { ctx.progress(p); };
  apt::AptSettings a;
  const int64_t N = sz.spp_pass * sz.res * sz.res;  // mutations per pass
  a.bootstrap = N / 2;                             // b's noise is common to all pixels: keep it below theirs
  a.chains = 1024;  // many short chains: a pass sums more independent starts (less skewed Welch samples)
  if (fault == AptFault::kNoRejectedSplat) a.splat_weight = mcmc::apt_splat_without_rejected;
  if (fault == AptFault::kBootstrapLastCandidate) a.bootstrap_sum = mcmc::apt_bootstrap_last_candidate;
  Film film(sz.res, sz.res);
  apt::AptStats stats;
  apt::run_apt(*world, st, a, film, &stats);
  const std::vector<double> visits = pss::expected_visits(ref->mean_image(), N);
  std::vector<bool> mask(visits.size());
  int64_t excluded = 0;
  for (size_t i = 0; i < visits.size(); ++i) excluded += (mask[i] = visits[i] < kMinVisits);
  WelchImage fa = film.welch(), fb = ref->welch();
  exclude_pixels(fa, fb, mask);
  const bool control = fault != AptFault::kNone;
  const ChannelCompare c = compare_channels(fa, fb, kAlpha);
  CheckResult r = compare_record(c, control, control ? name + " (broken variant)" : name);
  r.samples = stats.mutations;
  r.message += fmt::format(" [{} of {} pixels excluded: fewer than {} expected mutations per pass]; {}", excluded,
                           visits.size(), kMinVisits, stats.message());
  r.details["excluded_pixels"] = excluded;
  r.details["fault"] = static_cast<int>(fault);
  r.details["settings"] = {{"scene", scene}, {"resolution", sz.res}, {"passes", sz.passes},
                           {"mutations_per_pixel_per_pass", sz.spp_pass}, {"reference_spp_per_pass", sz.ref_spp_pass},
                           {"reference", "pt"}, {"max_depth", kMaxDepth}, {"seed", st.seed}, {"chains_per_pass", a.chains},
                           {"bootstrap", a.bootstrap}, {"large_step_probability", a.large_step_probability}};
  r.details["acceptance"] = {
      {"large", stats.large.proposed ? double(stats.large.accepted) / double(stats.large.proposed) : 0.0},
      {"small", stats.small.proposed ? double(stats.small.accepted) / double(stats.small.proposed) : 0.0},
      {"mutations_per_second", stats.mutations_per_second()}};
  const int64_t nonfinite = film.nonfinite().count() + ref->nonfinite().count();
  if (nonfinite > 0 || stats.step_errors > 0) {
    r.passed = false;
    r.message = fmt::format("{} non-finite samples, {} step errors; {}", nonfinite, stats.step_errors, r.message);
  }
  return r;
}

const bool registered = [] {
  struct Entry {
    std::string name, scene;
    AptFault fault;
    std::string description;
  };
  const std::vector<Entry> entries = {
      {"render.apt.cornell.unbiased", "cornell-box.json", AptFault::kNone,
       "apt (Zirr 2020 Sec. 7: APT small step + path-tracer multiple-try large step) against a longer path-tracer "
       "reference, Welch t-test per pixel over independent passes, alpha 0.01"},
      {"render.apt.glossy.unbiased", "glossy.json", AptFault::kNone,
       "apt against a longer path-tracer reference on the glossy scene, Welch t-test per pixel, alpha 0.01"},
      {"render.apt.negative_control.no_rejected_splat", "cornell-box.json", AptFault::kNoRejectedSplat,
       "apt without the (1 - a) splat of the current state must be rejected"},
      {"render.apt.negative_control.no_rejected_splat.glossy", "glossy.json", AptFault::kNoRejectedSplat,
       "apt without the (1 - a) splat of the current state must be rejected (glossy scene)"},
      {"render.apt.negative_control.bootstrap_last_candidate", "cornell-box.json", AptFault::kBootstrapLastCandidate,
       "apt normalised by b from the full-length candidate of each bootstrap draw (not the sum over its prefixes) "
       "must be rejected"},
  };
  for (const Entry& e : entries) {
    Registry::global().add(Check{.name = e.name,
                                 .description = e.description,
                                 .kind = CheckKind::kStatistical,
                                 .run = [e](const CheckContext& ctx) { return run_apt_image(ctx, e.scene, e.fault, e.name); }});
  }
  return true;
}();

}  // namespace
}  // namespace tb

#include "lib/mcmc/pss/pss_driver.h"

#include "lib/integrator/path_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "estimators/mcmc/acceptance.h"
#include "estimators/mcmc/kernel_step.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/film/film_tile.h"
#include "lib/path/light_sampler.h"

namespace tb {
namespace pss {

std::string PssStats::message() const {
  return fmt::format("{} mutations in {:.2f} s ({:.3g} /s in the mutation phase); acceptance: large step {:.3f} ({} of {}), small step "
                     "{:.3f} ({} of {}); {} bootstrap samples, b = {:.6g} (last pass); {} non-finite targets",
                     mutations, seconds, mutations_per_second(), large_acceptance(), large_accepted, large_proposed,
                     small_acceptance(), small_accepted, small_proposed, bootstrap_samples, last_b, nonfinite);
}

double PssStats::visits_cv() const {
  if (visits.empty()) return 0.0;
  double sum = 0.0, sq = 0.0;
  for (double v : visits) sum += v;
  const double mean = sum / static_cast<double>(visits.size());
  for (double v : visits) sq += (v - mean) * (v - mean);
  return mean > 0.0 ? std::sqrt(sq / static_cast<double>(visits.size())) / mean : 0.0;
}

void PssStats::add(const PssStats& o) {
  large_proposed += o.large_proposed;
  large_accepted += o.large_accepted;
  small_proposed += o.small_proposed;
  small_accepted += o.small_accepted;
  mutations += o.mutations;
  bootstrap_samples += o.bootstrap_samples;
  zero_passes += o.zero_passes;
  nonfinite += o.nonfinite;
  seconds += o.seconds;
  mutation_seconds += o.mutation_seconds;
  last_b = o.last_b;
  if (visits.size() < o.visits.size()) visits.resize(o.visits.size(), 0.0);
  for (size_t i = 0; i < o.visits.size(); ++i) visits[i] += o.visits[i];
}

std::vector<double> expected_visits(const std::vector<Rgb>& image, int64_t mutations) {
  double total = 0.0;
  for (const Rgb& c : image) total += luminance(c);
  std::vector<double> v(image.size(), 0.0);
  if (total > 0.0)
    for (size_t i = 0; i < image.size(); ++i) v[i] = static_cast<double>(mutations) * luminance(image[i]) / total;
  return v;
}

namespace {

constexpr uint64_t kBootstrapKey = hash_string("pss.bootstrap");
constexpr uint64_t kChainKey = hash_string("pss.chain.decisions");
constexpr uint64_t kStateKey = hash_string("pss.chain.uniforms");
constexpr uint64_t kPilotKey = hash_string("pss.pilot");

struct Chain {
  PssState state{Rng(), 0.01};
  Rng control;
  int level = 0;
  std::vector<Splat> current, proposed;
  double i_current = 0.0;
  double y_current = 0.0;      // target_value of the current splats (kSplatThroughput control)
  double sigma_current = 0.0;  // rescaled small step: sigma(x)
  double y_ref = 0.0;          // rescaled small step: Y_ref = b of the chain's group
  std::vector<std::pair<uint32_t, double>> where;  // visit counts: the current state's pixel shares
  std::vector<double> visits;
  int width = 0, height = 0;   // of the film (visit counts)
  double scale = 0.0;  // P b / N of the chain's group: the film weight of a splat v / I
  int64_t remaining = 0;
  uint64_t next_index = 0;  // sample index of the next mutation in the film's logs
  PssStats stats;
};

// Evaluates the sample function. A non-finite target sets *nonfinite (the caller counts it) and
// reads as 0, like a zero target: the state is never accepted, its splats never reach the film.
double evaluate(const SampleFunction& f, const TargetFunction& target, int level, StreamUniforms& u,
                std::vector<Splat>* out, bool* nonfinite) {
  out->clear();
  u.restart();
  f.sample(level, u, out);
  const double i = target ? target(*out) : target_value(*out);
  *nonfinite = !std::isfinite(i);
  if (*nonfinite || !(i > 0.0)) {
    out->clear();
    return 0.0;
  }
  return i;
}

void splat_all(SplatBuffer& buffer, const std::vector<Splat>& splats, double weight, uint64_t index) {
  if (weight == 0.0) return;
  for (const Splat& s : splats) buffer.splat(s.raster, s.value * weight, index);
}

// Where a state lies, for visit counts: one unit spread over the pixels of its splats in
// proportion to each splat's own target value pi({c}) (for PSSMLT its luminance; for multi-stage
// MLT, Y(v_c / I~(r_c))), i.e. each pixel's share of pi(x) = sum of the shares for a single splat.
// A state of BDPT splats both at its camera pixel and, through its t = 1 connections, elsewhere.
void visit_weights(const std::vector<Splat>& splats, const TargetFunction& target, int width, int height,
                   std::vector<std::pair<uint32_t, double>>* out) {
  out->clear();
  double total = 0.0;
  std::vector<Splat> one(1);
  for (const Splat& s : splats) {
    const int x = static_cast<int>(std::floor(s.raster.x)), y = static_cast<int>(std::floor(s.raster.y));
    if (x < 0 || y < 0 || x >= width || y >= height) continue;
    one[0] = s;
    const double w = target ? target(one) : luminance(s.value);
    if (!(w > 0.0) || !std::isfinite(w)) continue;
    out->push_back({static_cast<uint32_t>(y * width + x), w});
    total += w;
  }
  for (auto& [pixel, w] : *out) w /= total;
}

// One mutation of a chain: propose, accept or reject, splat expected values.
void mutate(const SampleFunction& f, const PssSettings& pss, Chain& c, SplatBuffer& buffer) {
  const bool large = c.control.uniform() < pss.large_step_probability;
  const bool rescaled = pss.rescale.enabled && !large;
  c.state.start_iteration(large, c.sigma_current);
  bool nonfinite = false;
  const double i_prop = evaluate(f, pss.target, c.level, c.state, &c.proposed, &nonfinite);
  c.stats.nonfinite += nonfinite;
  // The large step and the fixed small step are symmetric (pss_state.h): T cancels in the ratio.
  // The rescaled small step is not: T(y -> x) / T(x -> y) over D(x) ∩ D(y) (rescaled_step.h).
  double reverse_over_forward = 1.0, sigma_prop = 0.0;
  if (pss.rescale.enabled && i_prop > 0.0) {
    sigma_prop = pss.rescale.sigma(pss.sigma, c.y_ref, i_prop);
    if (rescaled && pss.fault != PssFault::kNoProposalRatio)
      reverse_over_forward = std::exp(c.state.log_small_step_ratio(c.sigma_current, sigma_prop));
  }
  const double a = mcmc::HastingsRatio{}(c.i_current, 1.0, i_prop, reverse_over_forward);
  // kSplatThroughput: the splat weight 1 / Y(f) instead of 1 / pi (differs only for custom targets).
  const bool throughput = pss.fault == PssFault::kSplatThroughput;
  const double y_prop = throughput && i_prop > 0.0 ? target_value(c.proposed) : i_prop;
  mcmc::Transition<const std::vector<Splat>*, int> t;
  t.current = &c.current;
  t.move = 0;
  t.proposed = &c.proposed;
  t.acceptance = a;
  const uint64_t index = c.next_index++;
  mcmc::splat_expected(t, [&](const std::vector<Splat>* s, double w) {
    if (s == &c.current) {
      if (pss.fault == PssFault::kNoRejectedSplat) return;
      splat_all(buffer, c.current, c.scale * w / (throughput ? c.y_current : c.i_current), index);
    } else {
      splat_all(buffer, c.proposed, c.scale * w / (throughput ? y_prop : i_prop), index);
    }
  });
  const bool accepted = c.control.uniform() < a;
  (large ? c.stats.large_proposed : c.stats.small_proposed)++;
  if (accepted) {
    (large ? c.stats.large_accepted : c.stats.small_accepted)++;
    c.state.accept();
    std::swap(c.current, c.proposed);
    c.i_current = i_prop;
    c.y_current = y_prop;
    c.sigma_current = sigma_prop;
    if (!c.visits.empty()) visit_weights(c.current, pss.target, c.width, c.height, &c.where);
  } else {
    c.state.reject();
  }
  for (const auto& [pixel, w] : c.where) c.visits[pixel] += w;
  ++c.stats.mutations;
}

}  // namespace

namespace {

// Mutations and chains of each level in a pass (see PssSettings::resample_levels).
struct LevelPlan {
  int64_t mutations = 0, chains = 0;
  int64_t first_chain = 0;  // index of the level's first chain
};

std::vector<LevelPlan> plan_levels(const std::vector<double>& pilot_b, int64_t N, int64_t C) {
  const size_t L = pilot_b.size();
  double sum = 0.0;
  for (double v : pilot_b) sum += v;
  std::vector<LevelPlan> plan(L);
  int64_t first = 0;
  for (size_t l = 0; l < L; ++l) {
    // Defensive mixture: every level keeps a tenth of its uniform share, so a level the pilot
    // missed is still sampled (its estimate stays unbiased, only noisier).
    const double frac = L == 1 ? 1.0 : (sum > 0.0 ? 0.9 * pilot_b[l] / sum : 0.0) + (sum > 0.0 ? 0.1 : 1.0) / double(L);
    LevelPlan& p = plan[l];
    p.chains = std::max<int64_t>(1, std::llround(double(C) * frac));
    p.mutations = std::max<int64_t>(p.chains, std::llround(double(N) * frac));
    p.first_chain = first;
    first += p.chains;
  }
  return plan;
}

}  // namespace

int64_t run_pss(const SampleFunction& f, const RenderSettings& st, const PssSettings& pss, Film& film,
                PssStats* stats_out) {
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t P = film.pixel_count();
  const int64_t passes = std::max<int64_t>(1, st.passes);
  const int64_t spp_pass = std::max<int64_t>(1, st.spp / passes);
  const int64_t N = pss.mutations_per_pass > 0 ? pss.mutations_per_pass : spp_pass * P;  // mutations per pass
  const int levels = std::max(1, f.levels);
  const int64_t per_level = std::max<int64_t>(1, (pss.bootstrap_for(N, levels) + levels - 1) / levels);
  const int64_t boot_n = per_level * levels;
  const int64_t segment = std::max<int64_t>(1, pss.segment);
  const bool resample = pss.resample_levels || levels == 1;
  PssStats total;
  if (pss.count_visits) total.visits.assign(static_cast<size_t>(P), 0.0);
  std::vector<double> boot(static_cast<size_t>(boot_n)), cdf(static_cast<size_t>(boot_n));
  std::vector<uint8_t> boot_nonfinite(static_cast<size_t>(boot_n));

  // Bootstrap of one pass (or of the pilot): I of boot_n fresh states, `per_level` per level.
  auto bootstrap = [&](uint64_t key, uint64_t base) {
    parallel_for(static_cast<size_t>(boot_n), [&](size_t i) {
      thread_local std::vector<Splat> sp;
      PssState s(Rng::for_sample(st.seed, key, base + i), pss.sigma);
      bool nonfinite = false;
      boot[i] = evaluate(f, pss.target, static_cast<int>(static_cast<int64_t>(i) / per_level), s, &sp, &nonfinite);
      boot_nonfinite[i] = nonfinite;
    });
    total.bootstrap_samples += boot_n;
    for (uint8_t v : boot_nonfinite) total.nonfinite += v;
    std::vector<double> b_level(static_cast<size_t>(levels), 0.0);
    for (int l = 0; l < levels; ++l) {
      double level_sum = 0.0;
      for (int64_t j = 0; j < per_level; ++j) level_sum += boot[static_cast<size_t>(l * per_level + j)];
      b_level[static_cast<size_t>(l)] = level_sum / static_cast<double>(per_level);
    }
    return b_level;
  };

  // Mutations per level: one group for PSSMLT and for pbrt-v3's resampled levels; otherwise one
  // chain set per level, sized by an independent pilot bootstrap (fixed for the whole run, so
  // the passes stay independent and each level's estimate exactly unbiased).
  std::vector<LevelPlan> plan;
  if (resample) {
    plan = {LevelPlan{N, std::clamp<int64_t>(pss.chains, 1, N), 0}};
  } else {
    plan = plan_levels(bootstrap(kPilotKey, 0), N, std::max<int64_t>(pss.chains, levels));
  }
  int64_t C = 0;
  for (const LevelPlan& p : plan) C += p.chains;
  std::vector<Chain> chains(static_cast<size_t>(C));
  std::vector<SplatBuffer> buffers(static_cast<size_t>(C), SplatBuffer(film.width(), film.height()));
  int64_t done = 0;
  for (int64_t pass = 0; pass < passes; ++pass) {
    if (st.interrupted && st.interrupted->load()) break;
    // 1. Bootstrap: b_l = mean of I over the level's samples (Kelemen 2002, Sec. 5.2).
    const uint64_t boot_base = static_cast<uint64_t>(pass * boot_n);
    const std::vector<double> b_level = bootstrap(kBootstrapKey, boot_base);
    double b = 0.0, acc = 0.0;
    for (double v : b_level) b += v;
    for (int64_t i = 0; i < boot_n; ++i) cdf[static_cast<size_t>(i)] = acc += boot[static_cast<size_t>(i)];
    total.last_b = b;
    if (!(acc > 0.0)) ++total.zero_passes;
    // 2. Chains start at bootstrap samples resampled in proportion to I (over all levels, or
    //    within the chain's level).
    for (size_t g = 0; g < plan.size(); ++g) {
      const LevelPlan& lp = plan[g];
      // The range of bootstrap samples the group resamples from, and its weight.
      const int64_t lo = resample ? 0 : static_cast<int64_t>(g) * per_level;
      const int64_t hi = resample ? boot_n : lo + per_level;
      const double base = lo > 0 ? cdf[static_cast<size_t>(lo - 1)] : 0.0;
      const double weight = cdf[static_cast<size_t>(hi - 1)] - base;
      // Each splat is v / I times its expected-value weight; the group estimates
      // P * b_group / N_group * sum (docs/mlt-pss.md, "Normalisation").
      const double b_group = resample ? b : b_level[g];
      const double scale = static_cast<double>(P) * b_group / static_cast<double>(lp.mutations);
      parallel_for(static_cast<size_t>(lp.chains), [&](size_t k) {
        const size_t ci = static_cast<size_t>(lp.first_chain) + k;
        Chain& c = chains[ci];
        const uint64_t gc = static_cast<uint64_t>(pass * C) + ci;
        c.control = Rng::for_sample(st.seed, kChainKey, gc);
        c.stats = {};
        c.visits.clear();
        c.where.clear();
        c.width = film.width();
        c.height = film.height();
        const double u = c.control.uniform() * weight + base;
        c.remaining = lp.mutations / lp.chains + (static_cast<int64_t>(k) < lp.mutations % lp.chains ? 1 : 0);
        c.next_index = gc << 32;  // film reproducer: (pass * chains + chain) * 2^32 + mutation
        c.scale = scale;
        if (!(weight > 0.0)) {  // nothing found at this level in this pass: it contributes 0
          c.remaining = 0;
          c.i_current = 0.0;
          return;
        }
        const auto it = std::upper_bound(cdf.begin() + lo, cdf.begin() + hi, u);
        const int64_t j = std::min<int64_t>(it - cdf.begin(), hi - 1);
        c.level = static_cast<int>(j / per_level);
        c.state = PssState(Rng::for_sample(st.seed, kBootstrapKey, boot_base + static_cast<uint64_t>(j)), pss.sigma);
        c.state.set_rescaled(pss.rescale.enabled);
        bool nonfinite = false;  // sample j was finite in the bootstrap: regenerated exactly
        c.i_current = evaluate(f, pss.target, c.level, c.state, &c.current, &nonfinite);
        c.state.commit_reads();
        c.state.set_rng(Rng::for_sample(st.seed, kStateKey, gc));
        c.y_current = pss.fault == PssFault::kSplatThroughput ? target_value(c.current) : c.i_current;
        // Y_ref of the rescaled step: b of the group per level (b_group / levels would do as well;
        // any fixed positive value keeps the kernel valid).
        c.y_ref = b_group;
        c.sigma_current = pss.rescale.enabled ? pss.rescale.sigma(pss.sigma, c.y_ref, c.i_current) : 0.0;
        if (pss.count_visits) {
          c.visits.assign(static_cast<size_t>(P), 0.0);
          visit_weights(c.current, pss.target, film.width(), film.height(), &c.where);
        }
      });
    }
    // 3. Mutations, in segments whose splat buffers are merged in chain order.
    const auto tm = std::chrono::steady_clock::now();
    for (bool more = true; more;) {
      parallel_for(static_cast<size_t>(C), [&](size_t ci) {
        Chain& c = chains[ci];
        SplatBuffer& buf = buffers[ci];
        buf.clear();
        for (int64_t m = 0; m < segment && c.remaining > 0; ++m, --c.remaining) mutate(f, pss, c, buf);
      });
      more = false;
      for (int64_t ci = 0; ci < C; ++ci) {
        film.merge_splats(buffers[static_cast<size_t>(ci)]);
        more = more || chains[static_cast<size_t>(ci)].remaining > 0;
      }
    }
    total.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - tm).count();
    for (const Chain& c : chains) {
      total.large_proposed += c.stats.large_proposed;
      total.large_accepted += c.stats.large_accepted;
      total.small_proposed += c.stats.small_proposed;
      total.small_accepted += c.stats.small_accepted;
      total.mutations += c.stats.mutations;
      total.nonfinite += c.stats.nonfinite;
      for (size_t i = 0; i < c.visits.size(); ++i) total.visits[i] += c.visits[i];
    }
    // 4. The splats carry their group's scale P b / N already.
    film.end_pass(1.0);
    ++done;
    st.progress(static_cast<double>(done) / static_cast<double>(passes));
    if (st.time_budget_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > st.time_budget_s)
      break;
  }
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (pss.print_stats) fmt::print(stderr, "{}\n", total.message());
  if (stats_out) *stats_out = total;
  return done;
}

}  // namespace pss

namespace pss {

void fill_report(const PssStats& s, RunReport* report, const char* small_step_name) {
  if (!report) return;
  report->mutations = {{"large step", s.large_proposed, s.large_accepted},
                       {small_step_name, s.small_proposed, s.small_accepted}};
  report->mutations_total = s.mutations;
  report->mutations_per_second = s.mutations_per_second();
}

}  // namespace pss

int64_t render_pssmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& p, Film& film,
                      pss::PssStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::bdpt_sample_function(ctx, film.width(), film.height(), settings.max_depth,
                                                          settings.fault);
  return pss::run_pss(f, settings, p, film, stats);
}

int64_t render_pssmlt_pt(const World& world, const RenderSettings& settings, const pss::PssSettings& p, Film& film,
                         pss::PssStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::radiance_sample_function(
      film.width(), film.height(), [&](const Vec2& raster, Uniforms& u) { return pt_sample(ctx, settings, raster, u); });
  return pss::run_pss(f, settings, p, film, stats);
}

int64_t render_mmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& p, Film& film,
                    pss::PssStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::mmlt_sample_function(ctx, film.width(), film.height(), settings.max_depth,
                                                          p.fault != pss::PssFault::kNoTechniqueCount);
  return pss::run_pss(f, settings, p, film, stats);
}

namespace {

// A registered PSS renderer: default settings (`adjust` may change them), statistics into the
// run report.
template <class Render, class Adjust>
int64_t render_reported(Render render, const World& world, const RenderSettings& settings, Film& film,
                        Adjust adjust, const char* small_step_name = "small step") {
  pss::PssSettings p;
  adjust(p);
  pss::PssStats stats;
  const int64_t passes = render(world, settings, p, film, &stats);
  pss::fill_report(stats, settings.report, small_step_name);
  return passes;
}

using RenderFn = int64_t (*)(const World&, const RenderSettings&, const pss::PssSettings&, Film&, pss::PssStats*);
constexpr auto kDefaults = [](pss::PssSettings&) {};

}  // namespace

int64_t render_pssmlt(const World& world, const RenderSettings& settings, Film& film) {
  return render_reported(static_cast<RenderFn>(render_pssmlt), world, settings, film, kDefaults);
}

int64_t render_pssmlt_pt(const World& world, const RenderSettings& settings, Film& film) {
  return render_reported(static_cast<RenderFn>(render_pssmlt_pt), world, settings, film, kDefaults);
}

int64_t render_mmlt(const World& world, const RenderSettings& settings, Film& film) {
  return render_reported(static_cast<RenderFn>(render_mmlt), world, settings, film, kDefaults);
}

int64_t render_pssmlt_pt_rescaled(const World& world, const RenderSettings& settings, Film& film) {
  return render_reported(
      static_cast<RenderFn>(render_pssmlt_pt), world, settings, film,
      [](pss::PssSettings& p) { p.rescale.enabled = true; }, "rescaled small step");
}

}  // namespace tb

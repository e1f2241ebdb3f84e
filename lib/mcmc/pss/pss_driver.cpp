#include "lib/mcmc/pss/pss_driver.h"

#include "lib/integrator/pass_loop.h"
#include "lib/integrator/path_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

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
                     "{:.3f} ({} of {}); {} bootstrap samples, b = {:.6g} (last pass); {} non-finite targets; {} step errors",
                     mutations, seconds, mutations_per_second(), large_acceptance(), large_accepted, large_proposed,
                     small_acceptance(), small_accepted, small_proposed, bootstrap_samples, last_b, nonfinite,
                     step_errors);
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
  step_errors += o.step_errors;
  for (const auto& [name, c] : o.components) {
    auto it = std::find_if(components.begin(), components.end(), [&](const auto& e) { return e.first == name; });
    if (it == components.end())
      components.push_back({name, c});
    else
      it->second.merge(c);
  }
  seconds += o.seconds;
  mutation_seconds += o.mutation_seconds;
  last_b = o.last_b;
  if (visits.size() < o.visits.size()) visits.resize(o.visits.size(), 0.0);
  for (size_t i = 0; i < o.visits.size(); ++i) visits[i] += o.visits[i];
}

PssStepSettings PssSettings::step_settings() const {
  PssStepSettings s;
  s.large_step_probability = large_step_probability;
  s.sigma = sigma;
  s.exponent = rescale.exponent;
  s.sigma_min = rescale.sigma_min;
  s.sigma_max = rescale.sigma_max;
  return s;
}

PssMutationList PssSettings::mutation_list() const {
  if (!mutations.empty()) return mutations;
  return make_pss_mutations({"large step", rescale.enabled ? "rescaled small step" : "small step"}, step_settings());
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

// A chain of a pass: the lazily updated state, its current splats (scored: I(x) cached) and the
// proposal slot, as the ScoredChain of estimators/mcmc/chain_step.h.
struct Chain {
  PssState state{Rng(), 0.01};
  Rng control;
  int level = 0;
  std::vector<Splat> current, proposed;
  double i_current = 0.0, i_proposed = 0.0;
  std::array<size_t, kStreams> reads_current{};  // D(x) of the current state
  double y_ref = 0.0;          // Y_ref of a rescaled step: b of the chain's group
  std::vector<std::pair<uint32_t, double>> where;  // visit counts: the current state's pixel shares
  std::vector<double> visits;
  int width = 0, height = 0;   // of the film (visit counts)
  double scale = 0.0;  // P b / N of the chain's group: the film weight of a splat v / I
  int64_t remaining = 0;
  uint64_t next_index = 0;  // sample index of the next mutation in the film's logs
  PssStats stats;
  std::vector<mcmc::ComponentCounts> counts;
  // Set per pass by the driver.
  const SampleFunction* f = nullptr;
  const PssSettings* pss = nullptr;
  const PssMutationList* mutations = nullptr;
  const std::vector<double>* selection = nullptr;  // c_k of the list (state-independent)
  const std::vector<double>* cumulative = nullptr;  // their running sums
  double scale_x = 0.0;  // the selected mutation's scale at x
  // The current state's scale for mutation scale_k (-1: none cached), and the proposal's.
  int scale_k = -1, pending_k = -1;
  double scale_current = 0.0, scale_pending = 0.0;

  // ---- ScoredChain -------------------------------------------------------------------------------
  int select(double v) const {  // inversion of the running sum of c_k (select_mutation's rule)
    const std::vector<double>& cdf = *cumulative;
    if (cdf.empty() || !(cdf.back() > 0.0)) return -1;
    const double target = v * cdf.back();
    int last = -1;
    for (size_t k = 0; k < cdf.size(); ++k) {
      const double w = cdf[k] - (k > 0 ? cdf[k - 1] : 0.0);
      if (w > 0.0) last = static_cast<int>(k);
      if (target < cdf[k] && w > 0.0) return static_cast<int>(k);
    }
    return last;
  }
  bool propose(int k, Uniforms&);
  mcmc::MoveTerms terms(int k);
  void accept();
  void reject() { state.reject(); }
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

bool Chain::propose(int k, Uniforms&) {
  const PssMutation& m = *(*mutations)[static_cast<size_t>(k)];
  scale_x = k == scale_k ? scale_current : m.scale(i_current, y_ref);
  m.begin(state, scale_x);
  bool nonfinite = false;
  i_proposed = evaluate(*f, pss->target, level, state, &proposed, &nonfinite);
  stats.nonfinite += nonfinite;
  return true;  // a PSS proposal never fails (a zero target is rejected by the rule)
}

mcmc::MoveTerms Chain::terms(int k) {
  const PssMutation& m = *(*mutations)[static_cast<size_t>(k)];
  const double c = (*selection)[static_cast<size_t>(k)];
  LazyPssMove mv(state);
  pending_k = -1;
  if (!m.symmetric() && i_proposed > 0.0) {  // the move's reads and scales enter only an asymmetric ratio
    mv.reads_x = reads_current;
    mv.reads_y = state.reads();
    mv.sigma_x = scale_x;
    mv.sigma_y = m.scale(i_proposed, y_ref);
    pending_k = k;
    scale_pending = mv.sigma_y;
  }
  return pss_move_terms(m, c, i_current, i_proposed, mv);
}

void Chain::accept() {
  scale_k = pending_k;
  scale_current = scale_pending;
  state.accept();
  reads_current = state.current_reads();
  std::swap(current, proposed);
  i_current = i_proposed;
  if (!visits.empty()) visit_weights(current, pss->target, width, height, &where);
}

// One mutation of a chain: the one step of estimators/mcmc/chain_step.h, splatting expected values.
void mutate(Chain& c, SplatBuffer& buffer) {
  const uint64_t index = c.next_index++;
  RngUniforms decisions(c.control);
  const PssSettings& pss = *c.pss;
  const mcmc::StepOutcome o = mcmc::chain_step(c, decisions, decisions, [&](mcmc::Which which, double w) {
    const bool cur = which == mcmc::Which::kCurrent;
    const std::vector<Splat>& splats = cur ? c.current : c.proposed;
    const double pi = cur ? c.i_current : c.i_proposed;
    if (!(pi > 0.0)) return;  // nothing to splat (the chain's start found no contribution)
    const double factor = pss.splat_weight ? pss.splat_weight(which, w, pi, splats) : w / pi;
    splat_all(buffer, splats, c.scale * factor, index);
  });
  if (o.component >= 0) c.counts[static_cast<size_t>(o.component)].add(o);
  c.stats.step_errors += o.status == mcmc::MoveStatus::kZeroForward || o.status == mcmc::MoveStatus::kNonFinite;
  for (const auto& [pixel, w] : c.where) c.visits[pixel] += w;
  ++c.stats.mutations;
}

}  // namespace

std::vector<double> effective_visits(const SampleFunction& f, const TargetFunction& target, int width, int height,
                                     int64_t mutations, int64_t n, uint64_t seed, bool resample_levels) {
  constexpr uint64_t kKey = hash_string("pss.effective_visits");
  constexpr size_t kChunks = 64;  // fixed chunks: sums independent of the thread count
  const int levels = std::max(1, f.levels);
  const size_t P = static_cast<size_t>(width) * static_cast<size_t>(height);
  n = std::max<int64_t>(1, n);
  // Per chunk and level: sum of pi, and per pixel the sums of Y_j and Y_j^2 / pi.
  struct Sums {
    std::vector<double> pi, y, y2;
  };
  std::vector<Sums> sums(kChunks);
  parallel_for(kChunks, [&](size_t chunk) {
    Sums& s = sums[chunk];
    s.pi.assign(static_cast<size_t>(levels), 0.0);
    s.y.assign(static_cast<size_t>(levels) * P, 0.0);
    s.y2.assign(static_cast<size_t>(levels) * P, 0.0);
    std::vector<Splat> sp;
    std::vector<std::pair<size_t, Rgb>> in_pixel;
    const int64_t lo = n * static_cast<int64_t>(chunk) / int64_t(kChunks), hi = n * static_cast<int64_t>(chunk + 1) / int64_t(kChunks);
    for (int l = 0; l < levels; ++l)
      for (int64_t i = lo; i < hi; ++i) {
        PssState st(Rng::for_sample(seed, kKey, static_cast<uint64_t>(l * n + i)), 0.01);
        sp.clear();
        st.restart();
        f.sample(l, st, &sp);
        const double pi = target ? target(sp) : target_value(sp);
        if (!std::isfinite(pi) || !(pi > 0.0)) continue;
        s.pi[static_cast<size_t>(l)] += pi;
        in_pixel.clear();
        for (const Splat& c : sp) {
          const int x = static_cast<int>(std::floor(c.raster.x)), y = static_cast<int>(std::floor(c.raster.y));
          if (x < 0 || y < 0 || x >= width || y >= height) continue;
          const size_t j = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
          auto it = std::find_if(in_pixel.begin(), in_pixel.end(), [j](const auto& e) { return e.first == j; });
          if (it == in_pixel.end()) in_pixel.push_back({j, c.value});
          else it->second += c.value;
        }
        for (const auto& [j, v] : in_pixel) {
          const double yj = std::max(0.0, luminance(v));
          s.y[static_cast<size_t>(l) * P + j] += yj;
          s.y2[static_cast<size_t>(l) * P + j] += yj * yj / pi;
        }
      }
  });
  std::vector<double> b(static_cast<size_t>(levels), 0.0), I(P, 0.0), var(P, 0.0);
  for (const Sums& s : sums)
    for (int l = 0; l < levels; ++l) b[static_cast<size_t>(l)] += s.pi[static_cast<size_t>(l)] / double(n);
  // One group over all levels (resample_levels): x ~ pi / sum_l b_l over (level, u), N mutations.
  double b_all = 0.0;
  for (double v : b) b_all += v;
  const std::vector<double> shares = resample_levels ? std::vector<double>(static_cast<size_t>(levels), 1.0) : level_shares(b);
  for (int l = 0; l < levels; ++l) {
    const double Nl = std::max(1.0, std::round(double(mutations) * shares[static_cast<size_t>(l)]));
    const double bl = resample_levels ? b_all : b[static_cast<size_t>(l)];
    for (size_t j = 0; j < P; ++j) {
      double y = 0.0, y2 = 0.0;
      for (const Sums& s : sums) {
        y += s.y[static_cast<size_t>(l) * P + j];
        y2 += s.y2[static_cast<size_t>(l) * P + j];
      }
      I[j] += y / double(n);
      var[j] += bl * (y2 / double(n)) / Nl;
    }
  }
  std::vector<double> out(P, 0.0);
  for (size_t j = 0; j < P; ++j) out[j] = var[j] > 0.0 ? I[j] * I[j] / var[j] : 0.0;
  return out;
}

std::vector<double> level_shares(const std::vector<double>& pilot_b) {
  const size_t L = pilot_b.size();
  double sum = 0.0;
  for (double v : pilot_b) sum += v;
  std::vector<double> shares(L, 1.0);
  if (L == 1) return shares;
  // Defensive mixture: every level keeps a tenth of its uniform share, so a level the pilot
  // missed is still sampled (its estimate stays unbiased, only noisier).
  for (size_t l = 0; l < L; ++l)
    shares[l] = (sum > 0.0 ? 0.9 * pilot_b[l] / sum : 0.0) + (sum > 0.0 ? 0.1 : 1.0) / double(L);
  return shares;
}

namespace {

// Mutations and chains of each level in a pass (see PssSettings::resample_levels).
struct LevelPlan {
  int64_t mutations = 0, chains = 0;
  int64_t first_chain = 0;  // index of the level's first chain
};

std::vector<LevelPlan> plan_levels(const std::vector<double>& pilot_b, int64_t N, int64_t C) {
  const size_t L = pilot_b.size();
  const std::vector<double> shares = level_shares(pilot_b);
  std::vector<LevelPlan> plan(L);
  int64_t first = 0;
  for (size_t l = 0; l < L; ++l) {
    const double frac = shares[l];
    LevelPlan& p = plan[l];
    p.chains = std::max<int64_t>(1, std::llround(double(C) * frac));
    p.mutations = std::max<int64_t>(p.chains, std::llround(double(N) * frac));
    p.first_chain = first;
    first += p.chains;
  }
  return plan;
}

}  // namespace

int64_t run_pss(const SampleFunction& f_in, const RenderSettings& st, const PssSettings& pss, Film& film,
                PssStats* stats_out) {
  const SampleFunction f = pss.wrap_sample ? pss.wrap_sample(f_in) : f_in;
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
  const PssMutationList mutations = pss.mutation_list();
  std::vector<double> selection, cumulative;
  for (size_t k = 0; k < mutations.size(); ++k) {
    selection.push_back(selection_probability(mutations, static_cast<int>(k)));
    cumulative.push_back(std::max(0.0, mutations[k]->weight()) + (k > 0 ? cumulative[k - 1] : 0.0));
  }
  PssStats total;
  for (const auto& m : mutations) total.components.push_back({m->name(), {}});
  if (pss.count_visits) total.visits.assign(static_cast<size_t>(P), 0.0);
  std::vector<double> boot(static_cast<size_t>(boot_n)), cdf(static_cast<size_t>(boot_n));
  std::vector<uint8_t> boot_nonfinite(static_cast<size_t>(boot_n));

  // Bootstrap of one pass (or of the pilot): I of boot_n fresh states, `per_level` per level.
  auto bootstrap = [&](uint64_t key, uint64_t base) {
    parallel_for(static_cast<size_t>(boot_n), [&](size_t i) {
      thread_local std::vector<Splat> sp;
      thread_local PssState s(Rng(), pss.sigma);  // storage reused across samples
      s.reset(Rng::for_sample(st.seed, key, base + i), pss.sigma);
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
  const int64_t done = for_each_pass_batch(st, passes, 1, [&](int64_t pass, int64_t) {
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
        c.counts.assign(mutations.size(), {});
        c.f = &f;
        c.pss = &pss;
        c.mutations = &mutations;
        c.selection = &selection;
        c.cumulative = &cumulative;
        c.scale_k = c.pending_k = -1;
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
        c.state.reset(Rng::for_sample(st.seed, kBootstrapKey, boot_base + static_cast<uint64_t>(j)), pss.sigma);
        bool nonfinite = false;  // sample j was finite in the bootstrap: regenerated exactly
        c.i_current = evaluate(f, pss.target, c.level, c.state, &c.current, &nonfinite);
        c.state.commit_reads();
        c.reads_current = c.state.current_reads();
        c.state.set_rng(Rng::for_sample(st.seed, kStateKey, gc));
        // Y_ref of the rescaled step: b of the group per level (b_group / levels would do as well;
        // any fixed positive value keeps the kernel valid).
        c.y_ref = b_group;
        if (pss.count_visits) {
          c.visits.assign(static_cast<size_t>(P), 0.0);
          visit_weights(c.current, pss.target, film.width(), film.height(), &c.where);
        }
      });
    }
    // 3. Mutations, in segments whose splat buffers are merged in chain order.
    const auto tm = std::chrono::steady_clock::now();
    run_chain_segments(chains, buffers, segment, film, [](Chain& c, SplatBuffer& buf) { mutate(c, buf); });
    total.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - tm).count();
    for (const Chain& c : chains) {
      for (size_t k = 0; k < c.counts.size() && k < mutations.size(); ++k) {
        total.components[k].second.merge(c.counts[k]);
        const bool large = mutations[k]->independent();
        (large ? total.large_proposed : total.small_proposed) += c.counts[k].proposed;
        (large ? total.large_accepted : total.small_accepted) += c.counts[k].accepted;
      }
      total.step_errors += c.stats.step_errors;
      total.mutations += c.stats.mutations;
      total.nonfinite += c.stats.nonfinite;
      for (size_t i = 0; i < c.visits.size(); ++i) total.visits[i] += c.visits[i];
    }
    // 4. The splats carry their group's scale P b / N already.
    film.end_pass(1.0);
  });
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (pss.print_stats) fmt::print(stderr, "{}\n", total.message());
  if (stats_out) *stats_out = total;
  return done;
}

}  // namespace pss

namespace pss {

void apply_params(const std::map<std::string, double>& params, PssSettings* p) {
  for (const auto& [name, v] : params) {
    if (name == "bootstrap" && v >= 1) p->bootstrap = static_cast<int64_t>(v);
    else if (name == "chains" && v >= 1) p->chains = static_cast<int64_t>(v);
    else if (name == "large_step" && v >= 0 && v <= 1) p->large_step_probability = v;
    else if (name == "sigma" && v > 0 && v < 1) p->sigma = v;
    else if (name == "resample_levels" && (v == 0 || v == 1)) p->resample_levels = v == 1;
    else
      throw std::invalid_argument(fmt::format("PSS parameter {} = {} is unknown or out of range (bootstrap >= 1, "
                                              "chains >= 1, 0 <= large_step <= 1, 0 < sigma < 1, resample_levels 0 or 1)",
                                              name, v));
  }
}

void fill_report(const PssStats& s, RunReport* report, const char* small_step_name) {
  if (!report) return;
  (void)small_step_name;
  report->mutations.clear();
  for (const auto& [name, c] : s.components) report->mutations.push_back({name, c.proposed, c.accepted, c.errors});
  report->mutations_total = s.mutations;
  report->mutations_per_second = s.mutations_per_second();
}

}  // namespace pss

int64_t render_pssmlt(const World& world, const RenderSettings& settings, const pss::PssSettings& p, Film& film,
                      pss::PssStats* stats) {
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const pss::SampleFunction f = pss::bdpt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
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
  const pss::SampleFunction f = pss::mmlt_sample_function(ctx, film.width(), film.height(), settings.max_depth);
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
  pss::apply_params(settings.params, &p);
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
